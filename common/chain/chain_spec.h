#pragma once
// The work unit of docs/design.md: everything a worker needs to run one chain and produce the same
// splats on any host, and what a chain reports back. For pt/bdpt a "chain" is a range of
// independent samples; for the Markov chain algorithms a chain started from a resampled seed
// path. Below mcmc/ and transport/ so that every chain kind shares it.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/chain/algorithm.h"
#include "common/film/pixel_allocation.h"
#include "common/film/splat_buffer.h"

namespace farm {

struct ChainSpec {
  std::string jobId;
  uint32_t chainIndex = 0;
  Algorithm algorithm = Algorithm::PSSMLT;
  uint64_t seed = 1;  // job seed; the chain's RNG stream is derived from (seed, index)
  int maxDepth = -1;  // longest path in edges (resolved; -1 unbounded)
  float largeStepProbability = 0.3f;
  // pssmlt, pssmlt-pt and mmlt: b * p_large of Kelemen et al. 2002's combination of the chain
  // with its own large steps by multiple importance sampling (section 4.1, the weights
  // 1 / (I / b + p_large)), with b the bootstrap's Z; 0: the chain alone (expected-value
  // splatting, each path weighted 1 / I). See runPssmltChain.
  double largeStepMis = 0;
  // pt/bdpt: global index of the first sample (the chain covers [firstSample, firstSample+budget))
  int64_t firstSample = 0;
  // pt/bdpt: where the samples land and which of the two estimators takes each cell of the film
  // (common/film/pixel_allocation.h); empty: uniform over the film, the algorithm's estimator
  // everywhere. Shared by a job's chains.
  std::shared_ptr<const PixelAllocation> pixelAllocation;
  // The seed: a primary-sample vector (pssmlt, pssmlt-pt, mmlt) or a serialized path (mlt),
  // and its scalar contribution I.
  std::vector<float> seedSample;
  std::string seedPath;
  double seedContribution = 0;
  MutationMix mutationMix;  // mlt
  // erpt: a tile of pixels [tileX, tileX + tileWidth) x [tileY, tileY + tileHeight); its budget
  // counts seeds, one pass over the tile's pixels after another. Each seed starts on average
  // erptChains chains of erptLength mutations that deposit erptDeposit luminance each.
  int tileX = 0, tileY = 0, tileWidth = 0, tileHeight = 0;
  double erptChains = 1;
  int erptLength = 100;
  double erptDeposit = 0;
  // mlt: before every seenEmissionEvery-th mutation (0: never) the chain takes one sample of
  // the lights the camera sees directly (common/transport/seen_emission.h), which
  // its target then leaves out, and splats it times seenEmissionScale = seenEmissionEvery / Z,
  // so that the image's one scale Z / mutations gives it path tracing's weight.
  int64_t seenEmissionEvery = 0;
  double seenEmissionScale = 0;
  // mlt through density grids: the estimate of each transmittance in f (see PathChain).
  int mediumSamples = 1;
  int mediumMarchSteps = 0;
  // mutations (pssmlt) or samples (pt/bdpt) this chain runs; < 0: until told to stop
  int64_t budget = 0;
  int64_t flushInterval = 0;  // mutations (or samples) between flushes
  // The independent group of chains this one belongs to: the coordinator sums each group's
  // flushes apart and estimates the image's error from the spread between the groups' images
  // (common/film/batch_means.h); a worker sums only flushes of one group into one upload.
  uint32_t errorGroup = 0;
  // Resume: the state a previous flush reported (empty: start from the seed); see ChainFlush.
  std::string resumeState;
  int64_t resumeMutations = 0;    // mutations already done when resumeState was taken
  uint32_t resumeFlushIndex = 0;  // flush index the resumed chain continues with
};

// Each chain's error group, in chain order.
inline std::vector<uint32_t> errorGroupsOf(const std::vector<ChainSpec>& chains) {
  std::vector<uint32_t> groups;
  groups.reserve(chains.size());
  for (const ChainSpec& c : chains) groups.push_back(c.errorGroup);
  return groups;
}

// How often one kind of proposal was made and accepted (PSSMLT's large and small steps, each of
// path-space MLT's mutations).
struct MutationTally {
  std::string name;
  int64_t proposed = 0;
  int64_t accepted = 0;
};

// Sums over a chain's large steps of the proposed path's scalar contribution I. A large step
// draws every primary sample afresh, so its I is an independent sample of the integrand whose
// mean is the normalization Z, as the bootstrap's candidates are (Kelemen et al. 2002 estimate
// their b from the large steps alone): pooled with the candidates, Z's error keeps falling while
// the chains run (common/mcmc/normalization.h). Zero for algorithms without large steps.
struct LargeStepSums {
  int64_t count = 0;
  double sum = 0;         // of I
  double sumSquares = 0;  // of I^2, for Z's standard error
  LargeStepSums& operator+=(const LargeStepSums& o) {
    count += o.count;
    sum += o.sum;
    sumSquares += o.sumSquares;
    return *this;
  }
  // What a flush from an honest chain can hold: counts and sums non-negative and finite.
  bool plausible() const {
    return count >= 0 && sum >= 0 && sumSquares >= 0 && sum < 1e300 && sumSquares < 1e300 &&
           (count > 0 || (sum == 0 && sumSquares == 0));
  }
};

// The splats of one flush: the change to the film since the chain's previous flush.
struct ChainFlush {
  uint32_t chainIndex = 0;
  uint32_t flushIndex = 0;  // 0, 1, 2, ... per chain
  int64_t mutations = 0;    // mutations (or samples) this flush covers
  int width = 0, height = 0;
  std::vector<float> splats;           // width*height*3, to be added (in double) to the chain sums
  InvalidSplats rejected;              // NaN, infinite or negative splats dropped at the source
  int64_t rays = 0;                    // rays traced for this flush's work (for rays per second)
  std::string state;                   // chain state after this flush (resume with ChainSpec)
  std::vector<MutationTally> tallies;  // proposals and acceptances in this flush, by kind
  LargeStepSums largeSteps;            // this flush's large steps (primary-sample chains)
  bool finished = false;               // the chain's budget is spent
};

}  // namespace farm
