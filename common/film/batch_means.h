#pragma once
// The error of an image estimated without a reference, by batch means: the chains of a job fall
// into G independent groups (ChainSpec::errorGroup), each group's image is an unbiased estimate
// of the whole on its own, and the spread between them estimates the variance of their
// work-weighted mean, the image the job shows. With W_g units of work in group g (W in all) and
// variance s^2 / W_g for group g's image, sum_g W_g (x_g - x)^2 has expectation (G - 1) s^2, so
//
//   Var(x) = s^2 / W  ~  sum_g W_g (x_g - x)^2 / ((G - 1) W)
//
// per channel value. A normalization constant Z that scales every group alike (the bootstrap's)
// moves them together, out of the spread's sight: its relative variance adds x^2 Var(Z)/Z^2.
// The relative MSE is then estimated as common/film/error_metrics.h measures it against a
// reference, mean of Var(x) / (r^2 + 0.01), with r^2 estimated without the reference: products
// of different groups' values (E[x_g x_h] = r^2 for g != h), averaged over the pixel's
// neighbours without the pixel itself (batch_means.cpp says why: a pixel alone cannot tell its
// firefly from its rare bright samples). Measured against the references at 2-6 s a render
// (every algorithm; cornell-box, veach-bidir, veach-mis, veach-ajar; seed 11): 0.72-1.32 of the
// reference's relative MSE, where the groups' median gave 0.28-23 (veach-ajar and veach-mis
// at few samples a pixel) and the image itself 0.3-1. Its limit: light that one group alone
// has found over a patch wider than the window. A firefly blob over darkness (erpt with two
// groups: r^2 estimated as blob x background, far above the truth) and a bright patch only one
// group's chains reached (r^2 estimated near 0) look alike to it; at seeds 12 and 13, 4 of 42
// such renders fell outside a factor of two (0.04, 0.23, 0.30 and 14). The numerator was right
// in each: with the reference's r^2 in the denominator, 0.92-1.20 of the measured error.
// What the spread cannot see: bias (an algorithm that misses light misses it in every group)
// and light no group has found yet: on water-caustic, where every local sampler misses a third
// of the light, it sees the noise and not the deficit.
#include <string>
#include <vector>

#include "common/film/image.h"

namespace farm {

struct ErrorEstimate {
  double relMse = 0;
  double rmse = 0;
};

// groups: the groups' images (G >= 2, each of image's size); work: their work (> 0 each);
// image: their work-weighted mean; zRelativeVariance: Var(Z) / Z^2 of a shared normalization
// (0: none). False with *error for fewer than two groups, sizes that differ or no work.
bool estimateError(const std::vector<Image>& groups, const std::vector<double>& work,
                   const Image& image, double zRelativeVariance, ErrorEstimate* out,
                   std::string* error);

}  // namespace farm
