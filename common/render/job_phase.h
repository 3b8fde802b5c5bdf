#pragma once
// Where a render job is in its life, from submission to its end: what the coordinator records
// and reports, and what `farm render` and `farm status` print (proto/convert.h takes it to and
// from the wire).

namespace farm {

enum class JobPhase {
  kSubmitted,
  kLoadingScene,
  kBootstrapping,
  kRendering,
  kFinishing,
  kDone,
  kFailed,
  kCancelled,
};

// Lowercase, as `farm status` and `farm list` print them ("loading-scene").
const char* jobPhaseName(JobPhase phase);

inline bool isTerminal(JobPhase p) {
  return p == JobPhase::kDone || p == JobPhase::kFailed || p == JobPhase::kCancelled;
}

}  // namespace farm
