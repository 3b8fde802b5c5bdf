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
// reference, mean of Var(x) / (r^2 + 0.01), with the median m of the groups' values in place of
// the reference r: the image x itself would put a firefly of one group into the denominator
// that should weigh it (x^2 grows as fast as the spread, and a pixel's share stays near 1
// whatever the firefly, where the reference's grows with it). Measured on cornell-box and
// veach-bidir, every algorithm, 4 s: within 0.95-1.5 of the reference's relative MSE with m,
// 0.10-0.98 with x.
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
