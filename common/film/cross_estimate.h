#pragma once
// The error of each of several independent images of the same scene, estimated from how they
// differ from one another, without a reference: the three-cornered hat (Gray and Allan 1974,
// for clocks none of which is known good). For independent images a, b with errors e_a, e_b
// against the truth r, E[(a - b)^2] = Var(a) + Var(b) + (bias_a - bias_b)^2, so with three,
//
//   e_a = (d_ab + d_ac - d_bc) / 2,   d_xy = mean of (x - y)^2 / (r^2 + 0.01),
//
// the relative MSE of common/film/error_metrics.h with r taken as the images' mean around the
// pixel (its neighbours', without its own: cross_estimate.cpp says why). Unlike the
// spread between one render's own chain groups (common/film/batch_means.h), this sees light
// that one estimator has not found yet and the others have: a pilot of pt that has not yet hit
// the light behind a slot shows little spread, but differs from bdpt's and pssmlt's images by
// that light. What it cannot see is light no image has found, or a bias they all share.
#include <vector>

#include "common/film/image.h"

namespace farm {

// For n >= 3 images of one size (width x height x 3 values): each one's relative MSE, the median
// over the pairs of the others of the formula above, at least 0. Empty for fewer than three or
// sizes that differ.
std::vector<double> crossEstimates(const std::vector<const Image*>& images);

}  // namespace farm
