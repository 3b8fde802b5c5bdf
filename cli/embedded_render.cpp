#include "cli/embedded_render.h"

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <thread>
#include <vector>

#include "cli/local_chain_source.h"
#include "coordinator/coordinator.h"
#include "worker/worker_pool.h"

namespace farm {
namespace fs = std::filesystem;

namespace {

// The coordinator core keeps blobs and the final image under a data directory; an embedded
// render needs it only while it runs.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "farm-render-XXXXXX").string();
    if (mkdtemp(pattern.data())) path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    if (!path_.empty()) fs::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace

Status renderEmbedded(const EmbeddedRenderOptions& options, EmbeddedRenderResult* result) {
  if (options.threads < 1 || options.workers < 1 || options.workers > options.threads) {
    return Status::invalidArgument("need 1 <= workers <= threads");
  }
  TempDir dataDir;
  if (dataDir.path().empty()) {
    return Status::internal("cannot create a temporary directory under " +
                            fs::temp_directory_path().string());
  }
  CoordinatorOptions coordinatorOptions;
  coordinatorOptions.dataDir = dataDir.path();
  coordinatorOptions.leaseSeconds = 3600;  // local workers die only with the whole process
  coordinatorOptions.tickSeconds = 0.05;
  Coordinator coordinator(coordinatorOptions);

  JobSpec spec;
  spec.settings = options.settings;
  spec.scenePath = options.scenePath;
  spec.referencePath = options.referencePath;
  spec.name = fs::path(options.scenePath).filename().string();
  std::string jobId;
  Status status = coordinator.submit(spec, &jobId);
  if (!status.isOk()) return status;

  // Worker pools, each with its share of the threads.
  std::vector<std::unique_ptr<LocalChainSource>> sources;
  std::vector<std::unique_ptr<WorkerPool>> pools;
  std::vector<std::thread> runners;
  std::vector<std::string> poolErrors(size_t(options.workers));
  for (int i = 0; i < options.workers; ++i) {
    const int threads = options.threads / options.workers + (i < options.threads % options.workers);
    sources.push_back(std::make_unique<LocalChainSource>(&coordinator, threads));
    WorkerPoolOptions poolOptions;
    poolOptions.threads = threads;
    poolOptions.idleRetrySeconds = 0.05;
    pools.push_back(std::make_unique<WorkerPool>(sources.back().get(), poolOptions));
  }
  for (int i = 0; i < options.workers; ++i) {
    runners.emplace_back([&, i] {
      try {
        pools[size_t(i)]->run();
      } catch (const std::exception& e) {
        poolErrors[size_t(i)] = e.what();
      }
    });
  }

  uint32_t seen = 0;
  JobPhase phase = JobPhase::kSubmitted;
  for (;;) {
    coordinator.waitForEnd(jobId, std::chrono::milliseconds(200), &phase);
    if (options.interrupted && options.interrupted->load() && !isTerminal(phase)) {
      coordinator.cancel(jobId, &phase);
    }
    if (options.onProgress) {
      JobProgress progress;
      coordinator.progress(jobId, seen > 0 ? seen - 1 : 0, &progress);
      seen = progress.errorSeriesTotal;
      options.onProgress(progress);
    }
    if (isTerminal(phase)) break;
  }
  for (auto& pool : pools) pool->stop();
  for (auto& runner : runners) runner.join();

  coordinator.progress(jobId, 0, &result->progress);
  switch (phase) {
    case JobPhase::kDone:
      return coordinator.finalImage(jobId, &result->image, &result->metadata);
    case JobPhase::kCancelled:
      return {StatusCode::kCancelled, "interrupted: the render was cancelled"};
    default:
      for (const std::string& e : poolErrors) {
        if (!e.empty()) return Status::internal(e);
      }
      return Status::failedPrecondition(result->progress.error);
  }
}

}  // namespace farm
