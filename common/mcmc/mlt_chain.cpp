#include "common/mcmc/mlt_chain.h"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "common/chain/chain_flusher.h"
#include "common/math/bytes.h"
#include "common/mcmc/mutations/bidirectional_mutation.h"
#include "common/mcmc/mutations/caustic_perturbation.h"
#include "common/mcmc/mutations/lens_perturbation.h"
#include "common/mcmc/mutations/lens_subpath_mutation.h"
#include "common/mcmc/mutations/multi_chain_perturbation.h"
#include "common/mcmc/mutations/mutation.h"
#include "common/mcmc/primary_sample_integrand.h"
#include "common/sampling/sampler.h"

namespace farm {

namespace {

constexpr uint64_t kMltChainDomain = 0x3175;
// "MST2": the RNG, the current path's estimate of f (pseudo-marginal chains keep it), the path.
constexpr uint32_t kStateMagic = 0x3254534d;

std::string serializeState(const Rng& rng, const Path& path, const PathContribution& f) {
  std::string s;
  appendBytes(s, kStateMagic);
  appendBytes(s, rng.state());
  appendBytes(s, rng.increment());
  appendBytes(s, f.logLuminance);
  appendBytes(s, f.color);
  appendBytes(s, f.film);
  return s + path.serialize();
}

bool deserializeState(const std::string& bytes, const Scene& scene, Rng* rng, Path* path,
                      PathContribution* f) {
  size_t at = 0;
  uint32_t magic;
  uint64_t state, inc;
  if (!readBytes(bytes, at, &magic) || magic != kStateMagic || !readBytes(bytes, at, &state) ||
      !readBytes(bytes, at, &inc) || !(inc & 1) || !readBytes(bytes, at, &f->logLuminance) ||
      !readBytes(bytes, at, &f->color) || !readBytes(bytes, at, &f->film) ||
      !std::isfinite(f->logLuminance) || !isFinite(f->color) || !std::isfinite(f->film.x) ||
      !std::isfinite(f->film.y) || !path->deserialize(bytes.substr(at), scene))
    return false;
  rng->restore(state, inc);
  return true;
}

}  // namespace

double logAcceptanceRatio(const Mutation& mutation, const Path& x, const PathContribution& fx,
                          const Path& y, const PathContribution& fy, const MutationRecord& record,
                          double selectX, double selectY) {
  if (!fx.carriesLight() || !fy.carriesLight() || !(selectX > 0) || !(selectY > 0))
    return -INFINITY;
  const double logR = fy.logLuminance - fx.logLuminance +
                      mutation.logDensity(y, x, record.reverse()) -
                      mutation.logDensity(x, y, record) + std::log(selectY) - std::log(selectX);
  return std::isnan(logR) ? -INFINITY : logR;
}

PathChain::PathChain(const Scene& scene, int maxDepth, const MutationMix& mix, int mediumSamples,
                     int marchSteps)
    : scene_(scene),
      context_{scene, maxDepth},
      bidirectional_(context_),
      lensSubpath_(context_),
      lens_(context_),
      caustic_(context_),
      multiChain_(context_),
      manifold_(context_),
      mutations_{&bidirectional_, &lensSubpath_, &lens_, &caustic_, &multiChain_, &manifold_},
      weights_{mix.bidirectional,          mix.lensSubpath,
               mix.lensPerturbation,       mix.causticPerturbation,
               mix.multiChainPerturbation, mix.manifoldPerturbation},
      mediumSamples_(std::max(mediumSamples, 1)),
      marchSteps_(std::max(marchSteps, 0)) {}

PathContribution PathChain::contribution(const Path& x, Rng& rng) const {
  if (seenEmissionApart_ && x.isSeenEmission(scene_)) return {};
  const TransmittanceEstimator estimator{&rng, mediumSamples_, marchSteps_};
  return x.contribution(scene_, context_.maxDepth, &estimator);
}

PathChain::Selection PathChain::select(const Path& x) const {
  Selection s;
  for (int i = 0; i < kMutationTypes; ++i) {
    if (weights_[i] > 0 && mutations_[i]->appliesTo(x)) s.total += s.probability[i] = weights_[i];
  }
  for (double& p : s.probability) p = s.total > 0 ? p / s.total : 0;
  return s;
}

bool PathChain::start(const Path& x, Rng& rng) {
  x_ = x;
  // A ratio-tracking estimate is 0 now and then (its roulette) where f is not: a chain can only
  // start where its estimate is positive.
  for (int attempt = 0; attempt < 16; ++attempt) {
    fx_ = contribution(x_, rng);
    if (fx_.carriesLight() || !scene_.hasMedia()) break;
  }
  sx_ = select(x_);
  return fx_.carriesLight();
}

void PathChain::resume(const Path& x, const PathContribution& fx) {
  x_ = x;
  fx_ = fx;
  sx_ = select(x_);
}

void PathChain::step(Rng& rng, SplatBuffer& film, float deposit, ChainFlusher* flusher) {
  double a = 0;
  int chosen = -1;
  PathContribution fy;
  Selection sy;
  if (sx_.total > 0) {
    double u = rng.nextDouble(), run = 0;
    for (int i = 0; i < kMutationTypes && chosen < 0; ++i) {
      run += sx_.probability[i];
      if (u < run && sx_.probability[i] > 0) chosen = i;
    }
    for (int i = kMutationTypes - 1; i >= 0 && chosen < 0; --i) {  // rounding at the top
      if (sx_.probability[i] > 0) chosen = i;
    }
    const Mutation& mutation = *mutations_[chosen];
    MutationRecord record;
    const bool tallyWalks = flusher && &mutation == &manifold_;
    ManifoldWalkStats walksBefore;
    if (tallyWalks) walksBefore = manifold_.walkStats();
    bool proposed = mutation.propose(x_, rng, &y_, &record);
    if (tallyWalks) {
      // The walks it ran (forward, and back to check the move reversible), and which converged.
      // The lost ones by cause, each as a share of every walk.
      const ManifoldWalkStats& after = manifold_.walkStats();
      const int64_t walks = int64_t(after.walks - walksBefore.walks);
      flusher->tally("manifold walk", walks, int64_t(after.converged - walksBefore.converged));
      for (int cause = 0; walks > 0 && cause < int(WalkLoss::kCount); ++cause) {
        flusher->tally(walkLossName(WalkLoss(cause)), walks,
                       int64_t(after.lost[cause] - walksBefore.lost[cause]));
      }
    }
    // A perturbation moves surface vertices only: one that would turn a vertex in a medium
    // into a surface's (or back) cannot be reversed, and is rejected.
    if (proposed && record.added == record.removed && chosen != int(MutationType::Bidirectional)) {
      for (size_t i = 0; i < x_.vertices.size() && proposed; ++i)
        proposed = inMedium(x_.vertices[i]) == inMedium(y_.vertices[i]);
    }
    if (proposed) {
      fy = contribution(y_, rng);
      if (fy.carriesLight()) {
        sy = select(y_);
        const double logR = logAcceptanceRatio(mutation, x_, fx_, y_, fy, record,
                                               sx_.probability[chosen], sy.probability[chosen]);
        a = logR >= 0 ? 1.0 : std::exp(logR);
      }
    }
  }
  if (a > 0) film.add(fy.film, fy.color, float(a) * deposit);
  if (a < 1) film.add(fx_.film, fx_.color, float(1 - a) * deposit);
  const bool accept = a >= 1 || (a > 0 && rng.nextDouble() < a);
  if (flusher && chosen >= 0) flusher->tally(mutationName(MutationType(chosen)), accept);
  if (accept) {
    std::swap(x_, y_);
    fx_ = fy;
    sx_ = sy;
  }
}

Rng mltChainRng(uint64_t seed, uint32_t chainIndex) {
  return Rng(seed, streamId(kMltChainDomain, chainIndex));
}

void runMltChain(const Scene& scene, const ChainSpec& spec,
                 const std::function<bool(ChainFlush&&)>& onFlush,
                 const std::atomic<bool>* cancel) {
  const std::string chain = "chain " + std::to_string(spec.chainIndex);
  Rng rng = mltChainRng(spec.seed, spec.chainIndex);
  Path x;
  PathChain walker(scene, spec.maxDepth, spec.mutationMix, spec.mediumSamples,
                   spec.mediumMarchSteps);
  // The spec says whether the chain's target leaves L E to its own sampler, as the
  // coordinator's bootstrap left them out of Z and the seeds (RenderJob::planChains); either
  // way the chain is exact for its target.
  const bool apart = spec.seenEmissionEvery > 0;
  if (apart && !(spec.seenEmissionScale > 0 && std::isfinite(spec.seenEmissionScale)))
    throw std::runtime_error(chain + ": its seen-emission scale is not a positive number");
  walker.setSeenEmissionApart(apart);
  const SeenEmission emission(scene);
  std::vector<Splat> splats;
  if (!spec.resumeState.empty()) {
    PathContribution fx;
    if (!deserializeState(spec.resumeState, scene, &rng, &x, &fx))
      throw std::runtime_error(chain + ": the resume state is corrupt");
    walker.resume(x, fx);
  } else if (spec.seedPath.empty() || !x.deserialize(spec.seedPath, scene)) {
    throw std::runtime_error(chain + " has no seed path of this scene");
  } else if (!walker.start(x, rng)) {
    throw std::runtime_error(chain + ": the seed path carries no light on this host");
  }
  ChainFlusher flusher(spec, scene, onFlush, cancel);
  while (flusher.budgetLeft()) {
    if (apart && flusher.done() % spec.seenEmissionEvery == 0) {
      // Before the mutation it precedes, so that a chain resumed at a flush takes the same.
      IndependentSampler sampler(&rng);
      const Vec2f p = primarySampleFilmPoint(scene.camera(), sampler);
      splats.clear();
      emission.sample(p, rng, &splats);
      for (const Splat& s : splats) {
        const Spectrum value = s.value * float(spec.seenEmissionScale);
        if (flusher.check(value)) flusher.film().add(s.film, value);
      }
    }
    walker.step(rng, flusher.film(), 1.0f, &flusher);
    if (!flusher.countMutation(walker.rays() + emission.rays(), [&] {
          return serializeState(rng, walker.current(), walker.currentContribution());
        }))
      return;
  }
}

}  // namespace farm
