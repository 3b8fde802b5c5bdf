#pragma once
// ERPT's seed paths through density grids (erpt.h). ERPT starts e / (N e_d) chains at a seed
// path of energy e, which puts chains at x in proportion to f(x) when e = f(x) / p(x) exactly.
// Path tracing's seeds through a grid are delta tracking's, whose distance density is the
// transmittance itself: p is unknown, and e only an estimate. A pseudo-marginal chain
// (Kronander et al. 2015, 3.3) is stationary on pairs (x, u) of a path and the numbers of its
// own estimate f^(x, u), with density f^(x, u) q(u); its chains must start there.
//
// So the seeds here come from a camera random walk whose every vertex has a density known in
// closed form (Path::densities, Medium::sampleFreeFlight's free flights: the path-space
// mutations' own), each path it builds (a light it hits, s = 0; next-event estimation to a light
// point at each vertex that is not specular, s = 1) weighted by the balance heuristic between
// the two, and its energy is e = f^(x, u) w_s(x) / p_s(x) with f^ the chain's own estimator
// (mediumSamples ratio-tracking estimates, or marching) on fresh numbers u. The chains start at
// (x, f^(x, u)): summed over the strategies, starts land at (x, u) with density
// f^(x, u) q(u) / (N e_d), the pseudo-marginal chain's stationary distribution, and ERPT stays
// unbiased through grids.
//
// The walk continues past depth kRouletteDepth with probability kContinue (a factor of every
// path's density, independent of its throughput so that both strategies can evaluate it).
#include <cstdint>
#include <functional>
#include <vector>

#include "common/mcmc/mutations/mutation.h"
#include "common/scene/scene.h"
#include "common/transport/path.h"

namespace farm {

// Whether the scene has a density grid (ERPT's seeds then come from GridSeedSampler).
bool hasDensityGrid(const Scene& scene);

struct GridSeed {
  const Path* path;
  PathContribution f;  // f^(x, u), the estimate the chains start with
  double energy;       // e = luminance(f^) w_s / p_s
  int strategy;        // 0: the walk hit the light; 1: next-event estimation
};

class GridSeedSampler {
 public:
  static constexpr int kRouletteDepth = 4;
  static constexpr double kContinue = 0.8;

  // rouletteDepth: the depth from which the walk continues with probability kContinue.
  GridSeedSampler(const Scene& scene, int maxDepth, int mediumSamples, int marchSteps,
                  int rouletteDepth = kRouletteDepth);

  // The seeds of one camera walk through film point `film` (uniform over its pixel, or over the
  // image: the energies are the splats of a film point uniform over the image, as path
  // tracing's values are), with numbers from rng. Seeds that carry no light are left out.
  void visit(const Vec2f& film, Rng& rng, const std::function<void(const GridSeed&)>& seed);

  // The density of the camera walk's continuation decisions that reach a vertex at `depth`.
  double continuationProbability(int depth) const;
  uint64_t rays() const { return context_.rays; }

 private:
  // Evaluates x (built by `strategy`) and passes it on when it carries light.
  void offer(int strategy, Rng& rng, const std::function<void(const GridSeed&)>& seed);

  const Scene& scene_;
  MutationContext context_;
  int mediumSamples_, marchSteps_, rouletteDepth_;
  std::vector<PathVertex> walk_;  // from the camera
  Path x_;
};

}  // namespace farm
