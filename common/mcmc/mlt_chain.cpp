#include "common/mcmc/mlt_chain.h"

#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "common/chain/chain_flusher.h"
#include "common/mcmc/mutations/bidirectional_mutation.h"
#include "common/mcmc/mutations/caustic_perturbation.h"
#include "common/mcmc/mutations/lens_perturbation.h"
#include "common/mcmc/mutations/lens_subpath_mutation.h"
#include "common/mcmc/mutations/multi_chain_perturbation.h"
#include "common/mcmc/mutations/mutation.h"

namespace farm {

namespace {

constexpr uint64_t kMltChainDomain = 0x3175;
constexpr uint32_t kStateMagic = 0x3154534d;  // "MST1"

std::string serializeState(const Rng& rng, const Path& path) {
  std::string s(sizeof(uint32_t) + 2 * sizeof(uint64_t), '\0');
  uint32_t magic = kStateMagic;
  uint64_t state = rng.state(), inc = rng.increment();
  std::memcpy(&s[0], &magic, sizeof magic);
  std::memcpy(&s[4], &state, sizeof state);
  std::memcpy(&s[12], &inc, sizeof inc);
  return s + path.serialize();
}

bool deserializeState(const std::string& bytes, const Scene& scene, Rng* rng, Path* path) {
  if (bytes.size() < 20) return false;
  uint32_t magic;
  uint64_t state, inc;
  std::memcpy(&magic, &bytes[0], sizeof magic);
  std::memcpy(&state, &bytes[4], sizeof state);
  std::memcpy(&inc, &bytes[12], sizeof inc);
  if (magic != kStateMagic || !(inc & 1) || !path->deserialize(bytes.substr(20), scene))
    return false;
  rng->restore(state, inc);
  return true;
}

// The mutation mix as selection probabilities over the mutations that apply to x.
struct Selection {
  double probability[kMutationTypes] = {};
  double total = 0;
};

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

bool mltChainPath(const std::string& state, const Scene& scene, std::string* pathBytes) {
  Rng rng;
  Path path;
  if (!deserializeState(state, scene, &rng, &path)) return false;
  *pathBytes = path.serialize();
  return true;
}

void runMltChain(const Scene& scene, const ChainSpec& spec,
                 const std::function<bool(ChainFlush&&)>& onFlush,
                 const std::atomic<bool>* cancel) {
  const std::string chain = "chain " + std::to_string(spec.chainIndex);
  MutationContext context{scene, spec.maxDepth};
  const BidirectionalMutation bidirectional(context);
  const LensSubpathMutation lensSubpath(context);
  const LensPerturbation lens(context);
  const CausticPerturbation caustic(context);
  const MultiChainPerturbation multiChain(context);
  const Mutation* mutations[kMutationTypes] = {&bidirectional, &lensSubpath, &lens, &caustic,
                                               &multiChain};
  const MutationMix& mix = spec.mutationMix;
  const double weights[kMutationTypes] = {mix.bidirectional, mix.lensSubpath, mix.lensPerturbation,
                                          mix.causticPerturbation, mix.multiChainPerturbation};
  auto select = [&](const Path& x) {
    Selection s;
    for (int i = 0; i < kMutationTypes; ++i) {
      if (weights[i] > 0 && mutations[i]->appliesTo(x)) s.total += s.probability[i] = weights[i];
    }
    for (double& p : s.probability) p = s.total > 0 ? p / s.total : 0;
    return s;
  };

  Rng rng(spec.seed, streamId(kMltChainDomain, spec.chainIndex));
  Path x;
  if (!spec.resumeState.empty()) {
    if (!deserializeState(spec.resumeState, scene, &rng, &x))
      throw std::runtime_error(chain + ": the resume state is corrupt");
  } else if (spec.seedPath.empty() || !x.deserialize(spec.seedPath, scene)) {
    throw std::runtime_error(chain + " has no seed path of this scene");
  }
  PathContribution fx = x.contribution(scene, spec.maxDepth);
  if (!fx.carriesLight())
    throw std::runtime_error(chain + ": the seed path carries no light on this host");
  Selection sx = select(x);

  ChainFlusher flusher(spec, scene, onFlush, cancel);
  SplatBuffer& film = flusher.film();
  Path y;
  MutationRecord record;
  while (flusher.budgetLeft()) {
    double a = 0;
    int chosen = -1;
    PathContribution fy;
    Selection sy;
    if (sx.total > 0) {
      double u = rng.nextDouble(), run = 0;
      for (int i = 0; i < kMutationTypes && chosen < 0; ++i) {
        run += sx.probability[i];
        if (u < run && sx.probability[i] > 0) chosen = i;
      }
      if (chosen < 0) {  // rounding at the top of the range
        for (int i = kMutationTypes - 1; i >= 0 && chosen < 0; --i)
          if (sx.probability[i] > 0) chosen = i;
      }
      const Mutation& mutation = *mutations[chosen];
      if (mutation.propose(x, rng, &y, &record)) {
        fy = y.contribution(scene, spec.maxDepth);
        if (fy.carriesLight()) {
          sy = select(y);
          const double logR = logAcceptanceRatio(mutation, x, fx, y, fy, record,
                                                 sx.probability[chosen], sy.probability[chosen]);
          a = logR >= 0 ? 1.0 : std::exp(logR);
        }
      }
    }
    if (a > 0) film.add(fy.film, fy.color, float(a));
    if (a < 1) film.add(fx.film, fx.color, float(1 - a));
    const bool accept = a >= 1 || (a > 0 && rng.nextDouble() < a);
    if (chosen >= 0) flusher.tally(mutationName(MutationType(chosen)), accept);
    if (accept) {
      std::swap(x, y);
      fx = fy;
      sx = sy;
    }
    if (!flusher.countMutation(context.rays, [&] { return serializeState(rng, x); })) return;
  }
}

}  // namespace farm
