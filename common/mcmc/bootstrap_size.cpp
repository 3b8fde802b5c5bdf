#include "common/mcmc/bootstrap_size.h"

#include <algorithm>
#include <cmath>

namespace farm {

double bootstrapCandidateCost(Algorithm algorithm) {
  // Candidates per second over work units per second, `farm render` at 256x256 and 16 per pixel
  // (mlt: 256, where a chain's fixed costs no longer hide its mutations') on two threads, on
  // cornell-box, veach-bidir, veach-ajar and water-caustic; the largest of the four, so that the
  // time share is a bound on all of them.
  switch (algorithm) {
    case Algorithm::PSSMLT:        // both evaluate one BDPT sample: 0.85 .. 1.0
    case Algorithm::PSSMLTOverPT:  // both one path-traced sample
      return 1.0;
    case Algorithm::MMLT:  // a candidate runs every strategy of one depth, a mutation one: 1.1
                           // .. 1.6
      return 1.6;
    case Algorithm::MLT:
      // A candidate builds every strategy's path (and manifold next-event estimation's, where
      // the scene has specular surfaces) while a mutation perturbs a few vertices: 15 .. 62
      // (the most where manifold next-event estimation walks through the water surface).
      return 64.0;
    case Algorithm::ERPT:  // an ERPT sample runs a whole set of short chains: 0.04
      return 0.04;
    case Algorithm::PathTracing:
    case Algorithm::Bidirectional:
      return 0.0;
  }
  return 0.0;
}

static int64_t clampCount(double n) {
  if (!(n > 0)) return 0;  // NaN too
  return int64_t(std::min(n, double(kBootstrapMaxCandidates)));
}

// N cost <= share (N cost + work): N <= share / (1 - share) * work / cost.
static int64_t countForTime(Algorithm algorithm, int64_t plannedWork) {
  const double cost = bootstrapCandidateCost(algorithm);
  if (!(cost > 0) || plannedWork <= 0) return 0;
  return clampCount(kBootstrapShare / (1 - kBootstrapShare) * double(plannedWork) / cost);
}

int64_t bootstrapPilot(Algorithm algorithm, int64_t plannedWork) {
  if (plannedWork <= 0) return kBootstrapPilot;
  return std::clamp(countForTime(algorithm, plannedWork), kBootstrapPilotFloor, kBootstrapPilot);
}

BootstrapSize bootstrapSize(Algorithm algorithm, int64_t plannedWork, int64_t pixels,
                            double relativeVariance) {
  BootstrapSize size;
  size.forTime = countForTime(algorithm, plannedWork);
  // sqrt(v / N) <= (1/3) / sqrt(M): N >= 9 v M.
  if (plannedWork > 0 && pixels > 0) {
    const double perPixel = double(plannedWork) / double(pixels);
    size.forError = clampCount(std::ceil(9 * std::max(0.0, relativeVariance) * perPixel));
  }
  size.candidates = std::clamp(std::max(size.forTime, size.forError),
                               bootstrapPilot(algorithm, plannedWork), kBootstrapMaxCandidates);
  return size;
}

}  // namespace farm
