#include "common/mcmc/bootstrap.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "common/mcmc/manifold_next_event.h"
#include "common/mcmc/primary_sample_integrand.h"
#include "common/mcmc/primary_sample_sampler.h"
#include "common/transport/bidirectional.h"
#include "common/transport/seen_emission.h"

namespace farm {

namespace {
constexpr uint64_t kCandidateDomain = 0xb007;
constexpr uint64_t kResampleDomain = 0x5eed;
}  // namespace

namespace {

// The paths of path-space MLT's candidate `index` and the luminance each carries: BDPT's
// strategies, less those of the paths that manifold next-event estimation takes over, then that
// estimator's own sample, from the same stream after BDPT's draws. The candidate's I is their
// sum; its seed path is drawn from them by share. The lights the camera sees directly (paths
// L E) are left to SeenEmission where it separates them: Z and the seeds are then those of the
// chains' target, which excludes those paths.
// Returns the connections manifold next-event estimation gave up on.
int64_t visitPathSpaceCandidate(const Scene& scene, int maxDepth, uint64_t seed, int64_t index,
                                const std::function<void(Path&&, double)>& visit) {
  const bool separated = SeenEmission::separates(scene);
  Rng rng(seed, streamId(kCandidateDomain, uint64_t(index)));
  IndependentSampler sampler(&rng);
  BidirectionalTracer tracer(scene, maxDepth);
  const ManifoldNextEvent manifold(scene, maxDepth);
  const bool manifoldActive = manifold.active();
  tracer.visitStrategies(primarySampleFilmPoint(scene.camera(), sampler), sampler,
                         [&](const BidirectionalTracer::StrategyPath& sp) {
                           const double share = luminance(sp.unweighted) * sp.weight;
                           if (!(share > 0) || !std::isfinite(share)) return;
                           Path x = Path::fromSubpaths(sp.light, sp.s, sp.camera, sp.t);
                           if (separated && x.isSeenEmission(scene)) return;
                           if (manifoldActive && manifold.covers(x)) return;
                           if (!x.contribution(scene, maxDepth, &kCarriesLightCheck).carriesLight())
                             return;
                           visit(std::move(x), share);
                         });
  // Its paths have a diffuse vertex (ManifoldNextEvent::covers): none is a light in view.
  manifold.sample(sampler, [&](const Path& x, double value) { visit(Path(x), value); });
  return int64_t(manifold.abandoned());
}

}  // namespace

double evaluateCandidate(const Scene& scene, Algorithm algorithm, int maxDepth, uint64_t seed,
                         int64_t index, std::vector<float>* primarySamples, int64_t* abandoned) {
  if (algorithm == Algorithm::MLT) {
    double sum = 0;
    const int64_t given = visitPathSpaceCandidate(scene, maxDepth, seed, index,
                                                  [&](Path&&, double share) { sum += share; });
    if (abandoned) *abandoned = given;
    return sum;
  }
  if (abandoned) *abandoned = 0;
  thread_local std::vector<Splat> splats;
  Rng rng(seed, streamId(kCandidateDomain, uint64_t(index)));
  RecordingSampler recorder(&rng);
  auto integrand = makePrimarySampleIntegrand(algorithm, scene, maxDepth);
  InvalidSplats rejected;  // a candidate's invalid splats are simply not counted in I
  double sum = evaluateContribution(*integrand, recorder, &splats, &rejected);
  if (primarySamples) *primarySamples = recorder.values();
  return sum;
}

bool candidatePath(const Scene& scene, int maxDepth, uint64_t seed, int64_t index, double u,
                   Path* path) {
  std::vector<Path> paths;
  std::vector<double> shares;
  double total = 0;
  visitPathSpaceCandidate(scene, maxDepth, seed, index, [&](Path&& x, double share) {
    paths.push_back(std::move(x));
    shares.push_back(share);
    total += share;
  });
  if (paths.empty()) return false;
  double target = u * total, run = 0;
  for (size_t i = 0; i < paths.size(); ++i) {
    run += shares[i];
    if (target < run || i + 1 == paths.size()) {
      *path = std::move(paths[i]);
      return true;
    }
  }
  return false;
}

void visitCandidateSplats(const Scene& scene, int maxDepth, uint64_t seed, int64_t index,
                          const std::function<void(const Splat&)>& visit) {
  visitPathSpaceCandidate(scene, maxDepth, seed, index, [&](Path&& x, double share) {
    const PathContribution c = x.contribution(scene, maxDepth);
    if (c.carriesLight()) visit({c.film, c.color * float(share)});
  });
}

BootstrapCandidates generateCandidates(const Scene& scene, Algorithm algorithm, int maxDepth,
                                       uint64_t seed, int64_t count,
                                       const std::function<bool(double)>& progress) {
  BootstrapCandidates out;
  if (!extendCandidates(scene, algorithm, maxDepth, seed, count, &out, progress)) return {};
  return out;
}

bool extendCandidates(const Scene& scene, Algorithm algorithm, int maxDepth, uint64_t seed,
                      int64_t count, BootstrapCandidates* out,
                      const std::function<bool(double)>& progress) {
  return extendCandidates(candidateEvaluator(scene, algorithm, maxDepth, seed), count, out,
                          progress);
}

CandidateEvaluator candidateEvaluator(const Scene& scene, Algorithm algorithm, int maxDepth,
                                      uint64_t seed) {
  return [&scene, algorithm, maxDepth, seed](int64_t index) {
    int64_t abandoned = 0;
    const double I =
        evaluateCandidate(scene, algorithm, maxDepth, seed, index, nullptr, &abandoned);
    return CandidateValue(I, abandoned);
  };
}

bool extendCandidates(const CandidateEvaluator& evaluate, int64_t count, BootstrapCandidates* out,
                      const std::function<bool(double)>& progress) {
  const int64_t first = int64_t(out->contributions.size());
  if (count <= first) return true;
  out->contributions.resize(size_t(count), 0.0);
  // Rounds of parallel work with a progress report (and a chance to cancel) between them; the
  // candidates do not depend on the rounds or the threads.
  const int64_t round = std::max<int64_t>((count - first) / 20, 4096);
  std::atomic<int64_t> abandoned{0};
  for (int64_t begin = first; begin < count; begin += round) {
    const int64_t end = std::min(count, begin + round);
    tbb::parallel_for(tbb::blocked_range<int64_t>(begin, end, 256),
                      [&](const tbb::blocked_range<int64_t>& r) {
                        int64_t given = 0;
                        for (int64_t k = r.begin(); k < r.end(); ++k) {
                          const CandidateValue v = evaluate(out->firstIndex + k);
                          out->contributions[size_t(k)] = v.contribution;
                          given += v.abandoned;
                        }
                        if (given) abandoned += given;
                      });
    if (progress && !progress(double(end - first) / double(count - first))) return false;
  }
  out->abandoned += abandoned.load();
  // Mean and standard error in double, summed in index order: the same on every host.
  double sum = 0, sumSq = 0;
  out->nonZero = 0;
  for (double c : out->contributions) {
    sum += c;
    sumSq += c * c;
    if (c > 0) ++out->nonZero;
  }
  const double n = double(count);
  out->mean = sum / n;
  double variance = count > 1 ? std::max(0.0, (sumSq - n * out->mean * out->mean) / (n - 1)) : 0;
  out->stdError = std::sqrt(variance / n);
  return true;
}

std::vector<int64_t> resampleSeeds(const std::vector<double>& contributions, int n, uint64_t seed) {
  std::vector<int64_t> picks;
  // Running sums: candidate i owns [cumulative[i-1], cumulative[i]), empty when it carries no
  // light, so a target that lands in a candidate's interval never picks a zero weight.
  std::vector<double> cumulative(contributions.size());
  double total = 0;
  size_t lastWithWeight = 0;
  for (size_t i = 0; i < contributions.size(); ++i) {
    if (contributions[i] > 0) {
      total += contributions[i];
      lastWithWeight = i;
    }
    cumulative[i] = total;
  }
  if (!(total > 0) || n <= 0) return picks;
  Rng rng(seed, streamId(kResampleDomain, 0));
  const double offset = rng.nextDouble();
  for (int k = 0; k < n; ++k) {
    // Each target from its own product (not a running sum of steps), and rounding that carries
    // it to the total or beyond lands on the last candidate with weight.
    const double target = (double(k) + offset) / double(n) * total;
    auto it = std::upper_bound(cumulative.begin(), cumulative.end(), target);
    size_t i = it == cumulative.end() ? lastWithWeight : size_t(it - cumulative.begin());
    picks.push_back(int64_t(i));
  }
  return picks;
}

}  // namespace farm
