#include "common/mcmc/pssmlt_chain.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/chain/chain_flusher.h"
#include "common/film/splat_buffer.h"
#include "common/mcmc/primary_sample_sampler.h"

namespace farm {

namespace {

constexpr uint64_t kChainDomain = 0xc4a1;

PrimarySampleSampler chainSampler(const ChainSpec& spec) {
  return PrimarySampleSampler(spec.seed, streamId(kChainDomain, spec.chainIndex),
                              spec.largeStepProbability);
}

// Rebuilds the path of the sampler's current vector without mutating it; returns its I.
double rebuildCurrentPath(const PrimarySampleIntegrand& integrand, PrimarySampleSampler& sampler,
                          std::vector<Splat>* splats, InvalidSplats* rejected) {
  sampler.setFrozen(true);
  sampler.startPath();
  double I = evaluateContribution(integrand, sampler, splats, rejected);
  sampler.setFrozen(false);
  return I;
}

}  // namespace

double seedContributionOf(const Scene& scene, const ChainSpec& spec) {
  auto integrand = makePrimarySampleIntegrand(spec.algorithm, scene, spec.maxDepth);
  PrimarySampleSampler sampler = chainSampler(spec);
  sampler.setSeed(spec.seedSample);
  std::vector<Splat> splats;
  InvalidSplats rejected;
  return rebuildCurrentPath(*integrand, sampler, &splats, &rejected);
}

void runPssmltChain(const Scene& scene, const ChainSpec& spec,
                    const std::function<bool(ChainFlush&&)>& onFlush,
                    const std::atomic<bool>* cancel) {
  auto integrand = makePrimarySampleIntegrand(spec.algorithm, scene, spec.maxDepth);
  runPssmltChain(scene, *integrand, spec, onFlush, cancel);
}

void runPssmltChain(const Scene& scene, const PrimarySampleIntegrand& integrand,
                    const ChainSpec& spec, const std::function<bool(ChainFlush&&)>& onFlush,
                    const std::atomic<bool>* cancel) {
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

  InvalidSplats rejected;
  std::vector<Splat> current, proposed;
  double currentI = rebuildCurrentPath(integrand, sampler, &current, &rejected);
  if (!(currentI > 0)) {
    throw std::runtime_error("chain " + std::to_string(spec.chainIndex) +
                             ": the seed path carries no light on this host");
  }

  // Kelemen's combination of the large steps with the chain (ChainSpec::largeStepMis). Its
  // large steps then are part of the image, not samples of Z: the image's scale is the
  // bootstrap's Z, which the weights' b must equal, so they are not reported for pooling.
  const double mis = spec.largeStepMis;
  const bool combined = mis > 0;

  ChainFlusher flusher(spec, scene, onFlush, cancel);
  SplatBuffer& film = flusher.film();
  flusher.reject(rejected);
  while (flusher.budgetLeft()) {
    sampler.startIteration();
    InvalidSplats dropped;
    double proposedI = evaluateContribution(integrand, sampler, &proposed, &dropped);
    flusher.reject(dropped);
    const bool largeStep = sampler.isLargeStep();
    if (largeStep && !combined) flusher.largeStep(proposedI);
    const double a = metropolisAcceptance(proposedI, currentI);
    // Kelemen et al. 2002, section 4.1: a path is sampled by the chain (density I / b) and,
    // with probability p_large, by the large step (density 1), so its balance-heuristic
    // estimate is f / (I / b + p_large), that is b f / (I + b p_large): the current path keeps
    // (1 - a), the proposal gets a, and a large step's proposal one more as an independent
    // sample. With mis = b p_large = 0 this is expected-value splatting, f / I.
    const double proposedShare = a + (largeStep && combined ? 1.0 : 0.0);
    if (proposedShare > 0 && proposedI > 0) {
      float w = float(proposedShare / (proposedI + mis));
      for (const Splat& s : proposed) film.add(s.film, s.value, w);
    }
    if (a < 1) {
      float w = float((1 - a) / (currentI + mis));
      for (const Splat& s : current) film.add(s.film, s.value, w);
    }
    if (a >= 1 || sampler.rng().nextDouble() < a) {
      std::swap(current, proposed);
      currentI = proposedI;
      sampler.accept();
      flusher.tally(largeStep ? "large step" : "small step", true);
    } else {
      sampler.reject();
      flusher.tally(largeStep ? "large step" : "small step", false);
    }
    if (!flusher.countMutation(integrand.rays(), [&] { return sampler.serialize(); })) return;
  }
}

}  // namespace farm
