#pragma once
// Runs a whole RenderJob in this process (bootstrap, every chain on the TBB pool, sums in
// double) with no coordinator: what the statistical tests and benchmarks of common/ use.
// `farm render` goes through the coordinator core instead, with the same chains.
#include <cstdint>

#include "common/render/render_job.h"

namespace farm {

struct LocalRenderResult {
  Image image;
  BootstrapResult bootstrap;
  int64_t work = 0;  // mutations or samples
  int64_t rejectedSplats = 0;
  double seconds = 0;
};

LocalRenderResult renderLocally(const RenderJob& job);

}  // namespace farm
