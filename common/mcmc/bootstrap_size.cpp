#include "common/mcmc/bootstrap_size.h"

#include <algorithm>
#include <chrono>
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

bool drawSizedCandidates(const CandidateEvaluator& evaluate, const BootstrapRequest& request,
                         SizedCandidates* out, const std::function<bool(double)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  *out = SizedCandidates();
  BootstrapCandidates& c = out->candidates;
  if (request.fixedCount > 0) return extendCandidates(evaluate, request.fixedCount, &c, progress);

  // The pilot, doubled until enough of it carries light to measure the relative variance.
  BootstrapCandidates pilot;
  int64_t count = bootstrapPilot(request.algorithm, request.plannedWork);
  if (!extendCandidates(evaluate, count, &pilot, progress)) return false;
  while (pilot.nonZero < kBootstrapPilotLight && count < kBootstrapPilotMax) {
    count = std::min(2 * count, kBootstrapPilotMax);
    if (!extendCandidates(evaluate, count, &pilot, progress)) return false;
  }
  if (pilot.nonZero == 0) {  // no light at all: Z = 0, which the caller refuses with the count
    c = std::move(pilot);
    return true;
  }
  out->pilot = count;

  // The candidates proper, from the pilot's end on: at least as many as the pilot, so that they
  // meet light about as often.
  c.firstIndex = count;
  int64_t fresh = count;
  if (request.plannedWork > 0) {
    out->size = bootstrapSize(request.algorithm, request.plannedWork, request.pixels,
                              pilot.relativeVariance());
    fresh = std::max(fresh, out->size.candidates);
    if (!extendCandidates(evaluate, fresh, &c, progress)) return false;
  } else {
    if (!extendCandidates(evaluate, fresh, &c, progress)) return false;
    if (request.timeBudgetSeconds > 0) {
      // A time budget: candidates until kBootstrapShare of it is spent, at the rate measured so
      // far (no job-independent count exists, and the work such a job does differs per run).
      const double budget = kBootstrapShare * request.timeBudgetSeconds;
      while (fresh < kBootstrapMaxCandidates && elapsed() < budget) {
        const double rate = double(count + fresh) / std::max(elapsed(), 1e-6);
        const int64_t more = int64_t(std::min(rate * (budget - elapsed()), double(fresh)));
        if (more < kBootstrapPilot) break;
        fresh = std::min(fresh + more, kBootstrapMaxCandidates);
        if (!extendCandidates(evaluate, fresh, &c, progress)) return false;
      }
      out->size.forTime = fresh;
    }
  }
  // Where the pilot met light but these candidates met none (light that rare), more of them until
  // some do: a stop their values decide, taken only where Z would otherwise be 0.
  while (c.nonZero == 0 && fresh < kBootstrapPilotMax) {
    fresh = std::min(2 * fresh, kBootstrapPilotMax);
    if (!extendCandidates(evaluate, fresh, &c, progress)) return false;
  }
  return true;
}

}  // namespace farm
