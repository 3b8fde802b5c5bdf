#pragma once
// `farm render`: the farm in one process. The network-free coordinator core bootstraps the job
// and sums flushes; local WorkerPools (one per --workers, splitting --threads) run its chains.
// Same plan, same chains, same image as a coordinator with remote workers.
#include <atomic>
#include <functional>
#include <string>

#include "common/film/image.h"
#include "coordinator/job.h"
#include "coordinator/status.h"

namespace farm {

struct EmbeddedRenderOptions {
  RenderSettings settings;
  std::string scenePath;
  std::string referencePath;                           // optional
  int threads = 1;                                     // chain threads in all
  int workers = 1;                                     // local worker pools sharing the threads
  std::function<void(const JobProgress&)> onProgress;  // a few times per second
  const std::atomic<bool>* interrupted = nullptr;      // when set: cancel the job
};

struct EmbeddedRenderResult {
  JobProgress progress;  // final, with the whole error series
  Image image;
  ImageMetadata metadata;
};

// Not OK when the job fails (the loader's or the bootstrap's message) or is interrupted.
Status renderEmbedded(const EmbeddedRenderOptions& options, EmbeddedRenderResult* result);

}  // namespace farm
