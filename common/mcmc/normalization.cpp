#include "common/mcmc/normalization.h"

#include <algorithm>
#include <cmath>

namespace farm {

Normalization pooledNormalization(double bootstrapMean, double bootstrapStdError,
                                  int64_t candidates, const LargeStepSums& largeSteps) {
  if (largeSteps.count <= 0 || candidates <= 0 || !largeSteps.plausible())
    return {bootstrapMean, bootstrapStdError, std::max<int64_t>(candidates, 0)};
  // The candidates' sums back from their mean and standard error (bootstrap.cpp's unbiased
  // sample variance: var = stdError^2 * n, over n - 1).
  const double nb = double(candidates);
  const double variance = bootstrapStdError * bootstrapStdError * nb;
  const double sum = bootstrapMean * nb + largeSteps.sum;
  const double sumSquares =
      variance * (nb - 1) + nb * bootstrapMean * bootstrapMean + largeSteps.sumSquares;
  const double n = nb + double(largeSteps.count);
  Normalization z;
  z.samples = candidates + largeSteps.count;
  z.value = sum / n;
  const double pooledVariance = std::max(0.0, (sumSquares - n * z.value * z.value) / (n - 1));
  z.stdError = std::sqrt(pooledVariance / n);
  return z;
}

}  // namespace farm
