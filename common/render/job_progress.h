#pragma once
// What the coordinator reports of a job while it runs and after: its phase, its work, its
// normalization, its error over time and its settings. `farm status`, `farm render`'s report and
// the live page read it; proto/convert.h takes it to and from the wire.
#include <cstdint>
#include <string>
#include <vector>

#include "common/chain/chain_spec.h"
#include "common/film/splat_buffer.h"
#include "common/render/job_phase.h"
#include "common/render/render_settings.h"

namespace farm {

// The image's error at one flush: against the reference (rmse, relMse; -1 without one) and
// estimated from the spread between the chains' groups (estimatedRelMse; -1 where the job has
// one group), common/film/batch_means.h.
struct ErrorSample {
  double elapsedSeconds = 0;
  int64_t samples = 0;
  double rmse = -1, relMse = -1;
  double estimatedRelMse = -1;
};

struct JobProgress {
  std::string jobId, name, error;
  JobPhase phase = JobPhase::kSubmitted;
  double fraction = 0, samplesPerSecond = 0, elapsedSeconds = 0, etaSeconds = -1;
  int64_t workDone = 0, plannedWork = 0;
  int64_t pilotWork = 0;                // of workDone, an allocation pilot's samples (kept)
  InvalidSplats rejected;               // splats dropped at the source, by cause
  int64_t rays = 0;                     // traced for the accepted work
  std::vector<MutationTally> tallies;   // proposals and acceptances by kind (Markov chains)
  std::vector<std::string> warnings;    // the scene loader's: what it left out or changed
  std::vector<std::string> renderPlan;  // the scene's plan, a line each (render_plan.h)
  std::vector<std::string> setAside;    // workers the job leases no more chains to, and why
  double raysPerSecond = 0;
  double normalization = 0, normalizationStdError = 0;
  int64_t bootstrapCandidates = 0;
  int64_t largeSteps = 0;  // the chains' large steps pooled into normalization (with the above)
  int64_t abandonedConnections = 0;  // BootstrapResult's: paths left out of normalization
  double loadSeconds = 0, bootstrapSeconds = 0, renderSeconds = 0;
  uint32_t chainsTotal = 0, chainsFinished = 0, chainsLeased = 0;
  uint32_t activeWorkers = 0;  // distinct workers holding a lease of the job's chains
  bool hasReference = false;
  std::vector<ErrorSample> errorSeries;  // from the index asked for
  uint32_t errorSeriesTotal = 0;
  int width = 0, height = 0;
  RenderSettings settings;
};

}  // namespace farm
