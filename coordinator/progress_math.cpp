#include "coordinator/progress_math.h"

#include <algorithm>

namespace farm {

ProgressEstimate estimateProgress(long long workDone, long long plannedWork,
                                  double timeBudgetSeconds, double elapsedSeconds,
                                  double renderSeconds) {
  ProgressEstimate p;
  if (renderSeconds > 0 && workDone > 0) p.samplesPerSecond = double(workDone) / renderSeconds;
  if (timeBudgetSeconds > 0) {
    p.fraction = std::clamp(elapsedSeconds / timeBudgetSeconds, 0.0, 1.0);
    p.etaSeconds = std::max(0.0, timeBudgetSeconds - elapsedSeconds);
    return p;
  }
  if (plannedWork <= 0) return p;
  p.fraction = std::clamp(double(workDone) / double(plannedWork), 0.0, 1.0);
  if (workDone >= plannedWork) {
    p.etaSeconds = 0;
  } else if (p.samplesPerSecond > 0) {
    p.etaSeconds = double(plannedWork - workDone) / p.samplesPerSecond;
  }
  return p;
}

}  // namespace farm
