#pragma once
// One chain of path-space MLT (Veach and Guibas 1997): its state is a Path, and each step picks
// one of Veach's mutations, with probability proportional to its weight among those that apply
// to the current path, and accepts the proposal with
//   a = min(1, f(y) T(x | y) P(mutation | y) / (f(x) T(y | x) P(mutation | x)))
// evaluated in logarithms (f(y) / f(x) from each path's log-luminance), so that neither long
// paths nor lights of 1e9 overflow or underflow it. Expected-value splatting as in PSSMLT:
// y's colour of unit luminance with weight a, x's with 1 - a; the image is Z / M times the sum.
#include <atomic>
#include <functional>

#include "common/chain/chain_flusher.h"
#include "common/chain/chain_spec.h"
#include "common/mcmc/mutations/bidirectional_mutation.h"
#include "common/mcmc/mutations/caustic_perturbation.h"
#include "common/mcmc/mutations/lens_perturbation.h"
#include "common/mcmc/mutations/lens_subpath_mutation.h"
#include "common/mcmc/mutations/manifold_perturbation.h"
#include "common/mcmc/mutations/multi_chain_perturbation.h"
#include "common/scene/scene.h"
#include "common/transport/seen_emission.h"

namespace farm {

// The Metropolis-Hastings step over path space that mlt's chains and ERPT's short chains share.
//
// In media f is evaluated with an estimate of each grid's transmittance (mediumSamples
// ratio-tracking estimates, or marching with marchSteps > 0): the pseudo-marginal chain of
// Kronander et al. 2015 (section 3.3), which keeps the estimate f^(x) with its state and
// accepts with f^(y) / f^(x), so that it is exactly distributed as f whatever the estimate's
// variance (more samples: fewer rejections for a lucky f^(x), at their cost).
class PathChain {
 public:
  PathChain(const Scene& scene, int maxDepth, const MutationMix& mix, int mediumSamples = 1,
            int marchSteps = 0);
  PathChain(const PathChain&) = delete;
  PathChain& operator=(const PathChain&) = delete;

  // Starts (or restarts) at x, estimating f(x) with numbers from rng (again, a few times, when
  // an estimate comes out 0); false when x carries no light.
  bool start(const Path& x, Rng& rng);
  // With `apart`, the chain's target leaves out the paths L E (f = 0 there), whose light
  // SeenEmission renders beside the chain (mlt's chains; ERPT's keep them, their seeds from
  // path tracing carry them). Before start().
  void setSeenEmissionApart(bool apart) { seenEmissionApart_ = apart; }
  // Resumes at x with the estimate its state kept.
  void resume(const Path& x, const PathContribution& fx);
  // One step: the proposal's colour with weight a * deposit and the current path's with
  // (1 - a) * deposit go to `film`; the proposal is tallied with `flusher` when given.
  void step(Rng& rng, SplatBuffer& film, float deposit, ChainFlusher* flusher = nullptr);
  const Path& current() const { return x_; }
  const PathContribution& currentContribution() const { return fx_; }
  uint64_t rays() const { return context_.rays; }

 private:
  struct Selection {
    double probability[kMutationTypes] = {};
    double total = 0;
  };
  Selection select(const Path& x) const;

  const Scene& scene_;
  MutationContext context_;
  BidirectionalMutation bidirectional_;
  LensSubpathMutation lensSubpath_;
  LensPerturbation lens_;
  CausticPerturbation caustic_;
  MultiChainPerturbation multiChain_;
  ManifoldPerturbation manifold_;
  const Mutation* mutations_[kMutationTypes];
  double weights_[kMutationTypes];
  PathContribution contribution(const Path& x, Rng& rng) const;

  int mediumSamples_, marchSteps_;
  bool seenEmissionApart_ = false;
  Path x_, y_;
  PathContribution fx_;
  Selection sx_;
};

// mlt's chains take one sample of the lights in view (seen_emission.h) before every this many
// mutations: a sample costs two rays against a mutation's several, and at 8 the film gets a
// sample per pixel for every 8 mutations per pixel, which leaves the lights' edges far less
// noisy than the chains' own share of the image.
constexpr int64_t kSeenEmissionEvery = 8;

// The random numbers of chain `chainIndex` of a job of `seed`: the worker's chain and the
// bootstrap (which checks that the chain can start from its seed) draw the same.
Rng mltChainRng(uint64_t seed, uint32_t chainIndex);

// Runs the chain of spec (seedPath, mutationMix, maxDepth) to its budget, flushing through
// onFlush; returns at once when *cancel becomes true. Throws std::runtime_error for a seed or
// resume state that is not a path of this scene, or a seed that carries no light.
void runMltChain(const Scene& scene, const ChainSpec& spec,
                 const std::function<bool(ChainFlush&&)>& onFlush,
                 const std::atomic<bool>* cancel = nullptr);

// log of the Metropolis-Hastings ratio of the move x -> y that `mutation` proposed with `record`,
// the mutation having been picked with probability selectX at x and selectY at y:
//   log f(y) - log f(x) + log T(x | y) - log T(y | x) + log selectY - log selectX,
// T(x | y) evaluated from y's vertices by the reverse move. -infinity when the move cannot be
// reversed; the acceptance is min(1, exp of it).
double logAcceptanceRatio(const Mutation& mutation, const Path& x, const PathContribution& fx,
                          const Path& y, const PathContribution& fy, const MutationRecord& record,
                          double selectX, double selectY);

}  // namespace farm
