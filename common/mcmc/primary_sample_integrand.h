#pragma once
// The function a primary-sample-space chain explores (Kelemen et al. 2002): an infinite vector
// of uniform numbers in, the splats of the sample it describes out. Its scalar contribution
// I(u) is the splats' total luminance, and E[I(u)] over uniform u is the normalization Z of
// every chain that walks on it; the bootstrap draws its candidates from the same function.
//
// Three such functions:
//  - BDPT (pssmlt): a film point, then one bidirectional sample with all (s, t) strategies;
//  - path tracing (pssmlt-pt): a film point, then one path-traced sample;
//  - multiplexed (mmlt, Hachisuka et al. 2014): the first two numbers choose a path length and
//    one (s, t) strategy of it, whose MIS-weighted contribution is divided by the probability
//    of that choice, so that a chain moves between lengths and strategies by itself.
#include <cstdint>
#include <memory>
#include <vector>

#include "common/chain/algorithm.h"
#include "common/film/splat_buffer.h"
#include "common/scene/scene.h"
#include "common/sampling/sampler.h"

namespace farm {

class PrimarySampleIntegrand {
 public:
  virtual ~PrimarySampleIntegrand() = default;
  // Appends the splats of the sample that the sampler's numbers describe.
  virtual void evaluate(Sampler& sampler, std::vector<Splat>* splats) const = 0;
  virtual uint64_t rays() const = 0;  // traced so far by this instance (one thread)
};

// The integrand of a primary-sample-space algorithm (pssmlt, pssmlt-pt, mmlt); also the BDPT
// one for mlt, whose bootstrap and seeds come from BDPT. maxDepth: longest path in edges, -1
// unbounded. Throws std::invalid_argument for an algorithm without one.
std::unique_ptr<PrimarySampleIntegrand> makePrimarySampleIntegrand(Algorithm algorithm,
                                                                   const Scene& scene,
                                                                   int maxDepth);

// The film point every integrand reads (after any technique choice): two numbers of the camera
// stream, uniform over the image.
Vec2f primarySampleFilmPoint(const Camera& camera, Sampler& sampler);

// Evaluates the integrand and keeps only finite, non-negative splats; returns I, their total
// luminance, and counts those dropped in *rejected.
double evaluateContribution(const PrimarySampleIntegrand& integrand, Sampler& sampler,
                            std::vector<Splat>* splats, InvalidSplats* rejected);

// Multiplexed MLT's choice of path length (in edges) from one uniform number: geometric with
// ratio kMultiplexedDepthRatio, truncated to 1..maxDepth when it is bounded, so that no length
// is left out and a large step proposes lengths roughly as often as light arrives along them.
// (Uniform over 1..maxDepth spent most large steps on long paths that carry almost nothing and
// cost the most: on the Cornell box, maxDepth 65, the mean proposed length was 33 edges.)
// *probability receives the choice's probability.
int chooseMultiplexedDepth(float u, int maxDepth, double* probability);
constexpr double kMultiplexedDepthRatio = 0.75;

}  // namespace farm
