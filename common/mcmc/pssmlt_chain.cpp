#include "common/mcmc/pssmlt_chain.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/film/splat_buffer.h"
#include "common/mcmc/primary_sample_sampler.h"
#include "common/render/chain_flusher.h"
#include "common/transport/bidirectional.h"

namespace farm {

namespace {

constexpr uint64_t kChainDomain = 0xc4a1;

// Builds the path the sampler's vector describes; returns I (total luminance) and drops
// splats that are not finite and non-negative, counting them.
double tracePath(const BidirectionalTracer& tracer, const Camera& camera, Sampler& sampler,
                 std::vector<Splat>* splats, int64_t* rejected) {
  splats->clear();
  Vec2f film(sampler.next(kCameraStream) * camera.width(),
             sampler.next(kCameraStream) * camera.height());
  tracer.sample(film, sampler, splats);
  double sum = 0;
  size_t kept = 0;
  for (const Splat& s : *splats) {
    if (!isValidRadiance(s.value)) {
      ++*rejected;
      continue;
    }
    (*splats)[kept++] = s;
    sum += luminance(s.value);
  }
  splats->resize(kept);
  return sum;
}

PrimarySampleSampler chainSampler(const ChainSpec& spec) {
  return PrimarySampleSampler(spec.seed, streamId(kChainDomain, spec.chainIndex),
                              spec.largeStepProbability);
}

// Rebuilds the path of the sampler's current vector without mutating it; returns its I.
double rebuildCurrentPath(const BidirectionalTracer& tracer, const Camera& camera,
                          PrimarySampleSampler& sampler, std::vector<Splat>* splats,
                          int64_t* rejected) {
  sampler.setFrozen(true);
  sampler.startPath();
  double I = tracePath(tracer, camera, sampler, splats, rejected);
  sampler.setFrozen(false);
  return I;
}

}  // namespace

double seedContributionOf(const Scene& scene, const ChainSpec& spec) {
  BidirectionalTracer tracer(scene, spec.maxDepth);
  PrimarySampleSampler sampler = chainSampler(spec);
  sampler.setSeed(spec.seedSample);
  std::vector<Splat> splats;
  int64_t rejected = 0;
  return rebuildCurrentPath(tracer, scene.camera(), sampler, &splats, &rejected);
}

void runPssmltChain(const Scene& scene, const ChainSpec& spec,
                    const std::function<bool(ChainFlush&&)>& onFlush,
                    const std::atomic<bool>* cancel) {
  const Camera& camera = scene.camera();
  BidirectionalTracer tracer(scene, spec.maxDepth);
  PrimarySampleSampler sampler = chainSampler(spec);
  if (!spec.resumeState.empty()) {
    if (!sampler.deserialize(spec.resumeState)) {
      throw std::runtime_error("chain " + std::to_string(spec.chainIndex) +
                               ": the resume state is corrupt");
    }
  } else {
    if (spec.seedSample.empty()) {
      throw std::runtime_error("chain " + std::to_string(spec.chainIndex) + " has no seed path");
    }
    sampler.setSeed(spec.seedSample);
  }

  int64_t rejected = 0;
  std::vector<Splat> current, proposed;
  double currentI = rebuildCurrentPath(tracer, camera, sampler, &current, &rejected);
  if (!(currentI > 0)) {
    throw std::runtime_error("chain " + std::to_string(spec.chainIndex) +
                             ": the seed path carries no light on this host");
  }

  ChainFlusher flusher(spec, scene, onFlush, cancel);
  SplatBuffer& film = flusher.film();
  flusher.rejectSplats(rejected);
  while (flusher.budgetLeft()) {
    sampler.startIteration();
    int64_t dropped = 0;
    double proposedI = tracePath(tracer, camera, sampler, &proposed, &dropped);
    flusher.rejectSplats(dropped);
    // Acceptance a = min(1, I(y) / I(x)) (Kelemen et al. 2002, eq. 6, symmetric proposals).
    double a = proposedI >= currentI ? 1.0 : proposedI / currentI;
    if (a > 0) {
      float w = float(a / proposedI);
      for (const Splat& s : proposed) film.add(s.film, s.value, w);
    }
    if (a < 1) {
      float w = float((1 - a) / currentI);
      for (const Splat& s : current) film.add(s.film, s.value, w);
    }
    if (a >= 1 || sampler.rng().nextDouble() < a) {
      std::swap(current, proposed);
      currentI = proposedI;
      sampler.accept();
    } else {
      sampler.reject();
    }
    if (!flusher.countMutation(tracer.rays(), [&] { return sampler.serialize(); })) return;
  }
}

}  // namespace farm
