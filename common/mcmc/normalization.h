#pragma once
// The normalization Z = E[I(u)] of the primary-sample chains (pssmlt, pssmlt-pt, mmlt), from
// every independent sample of I the job has: the bootstrap's candidates, fixed before the chains
// start, and the chains' large steps, which keep coming while they run (Kelemen et al. 2002, who
// estimate their b from the large steps alone). Both draw u uniformly from the same integrand,
// so pooled they are one sample, and Z's relative error falls as the render goes on where the
// bootstrap's alone stays put: with a heavy-tailed I (light through glass) that error was 5-16%
// and decided the channel means of the corpus's lights in glass (docs/corpus.md).
//
// The image is Z times the splats' mean, and Z now shares the large steps with the splats: a
// ratio of two consistent estimators, with a bias of order 1/(large steps), far below the
// standard errors the renders are held to.
#include <cstdint>

#include "common/chain/chain_spec.h"

namespace farm {

struct Normalization {
  double value = 0;     // Z
  double stdError = 0;  // its Monte Carlo standard error
  int64_t samples = 0;  // candidates and large steps
};

// Z pooled from the bootstrap's `candidates` (their mean and its standard error) and the chains'
// large steps. Without large steps, the bootstrap's figures as they are.
Normalization pooledNormalization(double bootstrapMean, double bootstrapStdError,
                                  int64_t candidates, const LargeStepSums& largeSteps);

}  // namespace farm
