#include "common/render/job_phase.h"

namespace farm {

const char* jobPhaseName(JobPhase phase) {
  switch (phase) {
    case JobPhase::kSubmitted:
      return "submitted";
    case JobPhase::kLoadingScene:
      return "loading-scene";
    case JobPhase::kBootstrapping:
      return "bootstrapping";
    case JobPhase::kRendering:
      return "rendering";
    case JobPhase::kFinishing:
      return "finishing";
    case JobPhase::kDone:
      return "done";
    case JobPhase::kFailed:
      return "failed";
    case JobPhase::kCancelled:
      return "cancelled";
  }
  return "unknown";
}

}  // namespace farm
