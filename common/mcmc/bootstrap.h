#pragma once
// The bootstrap of MLT (Veach 1997, 11.3; the thesis chapter in ../shared/seeds): many
// independent BDPT samples estimate the normalization constant Z = E[I(u)], the expected scalar
// contribution of one sample, and serve as candidates from which seed paths are resampled in
// proportion to I(u), so chains start in the stationary distribution and need no burn-in.
#include <cstdint>
#include <functional>
#include <vector>

#include "common/chain/algorithm.h"
#include "common/scene/scene.h"

namespace farm {

struct BootstrapCandidates {
  std::vector<double> contributions;  // I(u_i) per candidate
  double mean = 0, stdError = 0;
  int64_t nonZero = 0;
};

// I(u) for the candidate with index i of a job with `seed`: the algorithm's primary-sample
// integrand (see primary_sample_integrand.h) evaluated on stream (seed, i). Returns the splats'
// total luminance and, when asked, the primary-sample vector it used.
double evaluateCandidate(const Scene& scene, Algorithm algorithm, int maxDepth, uint64_t seed,
                         int64_t index, std::vector<float>* primarySamples = nullptr);

// Generates `count` candidates in parallel. `progress` receives the fraction done and may return
// false to cancel (then the result is empty).
BootstrapCandidates generateCandidates(const Scene& scene, Algorithm algorithm, int maxDepth,
                                       uint64_t seed, int64_t count,
                                       const std::function<bool(double)>& progress = {});

// Draws `n` candidate indices with probability proportional to contribution (systematic
// resampling with one random offset, which keeps the draws stratified).
std::vector<int64_t> resampleSeeds(const std::vector<double>& contributions, int n, uint64_t seed);

}  // namespace farm
