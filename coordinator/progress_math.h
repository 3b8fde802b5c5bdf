#pragma once
// How far along a job is, from the counts docs/design.md makes exact: work (mutations or samples)
// accepted over work planned, or wall-clock time over the budget for time-limited jobs.

namespace farm {

struct ProgressEstimate {
  double fraction = 0;          // [0, 1]
  double samplesPerSecond = 0;  // accepted work per second of rendering
  double etaSeconds = -1;       // < 0: unknown (nothing accepted yet)
};

// workDone/plannedWork: accepted and planned work (plannedWork <= 0 for time budgets);
// timeBudgetSeconds > 0 selects the time-based estimate, measured on elapsedSeconds (since the
// job started); renderSeconds is the time since chains were first leased, the denominator of
// the rate (bootstrap time would otherwise understate it).
ProgressEstimate estimateProgress(long long workDone, long long plannedWork,
                                  double timeBudgetSeconds, double elapsedSeconds,
                                  double renderSeconds);

}  // namespace farm
