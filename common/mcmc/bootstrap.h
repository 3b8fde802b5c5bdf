#pragma once
// The bootstrap of MLT (Veach 1997, 11.3; the thesis chapter in ../shared/seeds): many
// independent BDPT samples estimate the normalization constant Z = E[I(u)], the expected scalar
// contribution of one sample, and serve as candidates from which seed paths are resampled in
// proportion to I(u), so chains start in the stationary distribution and need no burn-in.
#include <cstdint>
#include <functional>
#include <vector>

#include "common/chain/algorithm.h"
#include "common/film/splat_buffer.h"
#include "common/scene/scene.h"
#include "common/transport/path.h"

namespace farm {

struct BootstrapCandidates {
  // I(u_i) per candidate: contributions[k] is the candidate of stream index firstIndex + k (the
  // index evaluateCandidate(), candidatePath() and a chain's seed take).
  std::vector<double> contributions;
  int64_t firstIndex = 0;
  double mean = 0, stdError = 0;
  int64_t nonZero = 0;
  // Connections manifold next-event estimation gave up on (ManifoldNextEvent::abandoned), each a
  // path left out of its candidate's I.
  int64_t abandoned = 0;
  // Var(I) / mean(I)^2, the square of Z's relative standard error times the count.
  double relativeVariance() const {
    return mean > 0 ? stdError * stdError * double(contributions.size()) / (mean * mean) : 0.0;
  }
};

// I(u) for the candidate with index i of a job with `seed`: the algorithm's primary-sample
// integrand (see primary_sample_integrand.h) evaluated on stream (seed, i). Returns the splats'
// total luminance and, when asked, the primary-sample vector it used. For path-space MLT, the
// luminance of the paths candidatePath() draws from: BDPT's, and where the scene has specular
// surfaces, those of manifold next-event estimation in place of BDPT's of their kind
// (manifold_next_event.h), which BDPT finds only through camera paths that hit the light.
// `abandoned`, when given, receives the connections manifold next-event estimation gave up on.
double evaluateCandidate(const Scene& scene, Algorithm algorithm, int maxDepth, uint64_t seed,
                         int64_t index, std::vector<float>* primarySamples = nullptr,
                         int64_t* abandoned = nullptr);

// Path-space seeds (mlt): candidate `index` rebuilt as the paths its sample built (BDPT's
// strategies and manifold next-event estimation's paths, as evaluateCandidate() sums them), one
// chosen in proportion to the luminance it carries (u uniform in [0, 1)), among those whose path
// carries light. Resampling candidates by I and then a strategy by its share
// of I gives paths distributed as the luminance of f (Veach 1997, 11.3). False when none does.
bool candidatePath(const Scene& scene, int maxDepth, uint64_t seed, int64_t index, double u,
                   Path* path);

// Candidate `index`'s paths (mlt), as candidatePath() draws from them, each as the splat a chain
// makes for it: at its film point, with f's colour and the share of I the path carries as its
// luminance. Summed over candidates and divided by their count, they are an image of the chains'
// target (its total Z; no lights seen directly where SeenEmission separates them) that shares
// nothing with the chains' mutations: a check of where mlt's chains put the light, on scenes
// where BDPT alone would not converge (the water caustic under its small light).
void visitCandidateSplats(const Scene& scene, int maxDepth, uint64_t seed, int64_t index,
                          const std::function<void(const Splat&)>& visit);

// I(u) of the candidate with stream index `index` and the connections given up on the way:
// evaluateCandidate() with the job's scene, algorithm, depth and seed bound, or any other
// integrand's (the tests' heavy-tailed ones).
struct CandidateValue {
  CandidateValue(double contribution = 0, int64_t abandoned = 0)  // NOLINT: a plain I converts
      : contribution(contribution), abandoned(abandoned) {}
  double contribution;
  int64_t abandoned;
};
using CandidateEvaluator = std::function<CandidateValue(int64_t index)>;
// evaluateCandidate() for a job's scene, algorithm, depth and seed (the scene is held by
// reference).
CandidateEvaluator candidateEvaluator(const Scene& scene, Algorithm algorithm, int maxDepth,
                                      uint64_t seed);

// Generates `count` candidates in parallel. `progress` receives the fraction done and may return
// false to cancel (then the result is empty).
BootstrapCandidates generateCandidates(const Scene& scene, Algorithm algorithm, int maxDepth,
                                       uint64_t seed, int64_t count,
                                       const std::function<bool(double)>& progress = {});

// `out` extended to `count` candidates (stream indices out->firstIndex + its size on), and the
// figures over all of them; false when cancelled (then `out` is unusable).
bool extendCandidates(const Scene& scene, Algorithm algorithm, int maxDepth, uint64_t seed,
                      int64_t count, BootstrapCandidates* out,
                      const std::function<bool(double)>& progress = {});
bool extendCandidates(const CandidateEvaluator& evaluate, int64_t count, BootstrapCandidates* out,
                      const std::function<bool(double)>& progress = {});

// Draws `n` positions in `contributions` with probability proportional to contribution (systematic
// resampling with one random offset, which keeps the draws stratified).
std::vector<int64_t> resampleSeeds(const std::vector<double>& contributions, int n, uint64_t seed);

}  // namespace farm
