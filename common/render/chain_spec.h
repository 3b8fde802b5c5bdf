#pragma once
// The work unit of DESIGN.md: everything a worker needs to run one chain and produce the same
// splats on any host. For pt/bdpt a "chain" is a range of independent samples; for pssmlt a
// Markov chain started from a resampled seed path.
#include <cstdint>
#include <string>
#include <vector>

#include "common/render/render_settings.h"

namespace farm {

struct ChainSpec {
  std::string jobId;
  uint32_t chainIndex = 0;
  Algorithm algorithm = Algorithm::PSSMLT;
  uint64_t seed = 1;  // job seed; the chain's RNG stream is derived from (seed, index)
  int maxDepth = -1;  // longest path in edges (resolved; -1 unbounded)
  float largeStepProbability = 0.3f;
  // pt/bdpt: global index of the first sample (the chain covers [firstSample, firstSample+budget))
  int64_t firstSample = 0;
  // pssmlt: the seed path as its primary-sample vector, and its scalar contribution I(u)
  std::vector<float> seedSample;
  double seedContribution = 0;
  // mutations (pssmlt) or samples (pt/bdpt) this chain runs; < 0: until told to stop
  int64_t budget = 0;
  int64_t flushInterval = 0;  // mutations (or samples) between flushes
  // Resume: the state a previous flush reported (empty: start from the seed); see ChainFlush.
  std::string resumeState;
  int64_t resumeMutations = 0;    // mutations already done when resumeState was taken
  uint32_t resumeFlushIndex = 0;  // flush index the resumed chain continues with
};

}  // namespace farm
