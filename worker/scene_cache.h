#pragma once
// A worker's scenes: bundles fetched once per content hash into a cache directory (kept across
// runs, shared by jobs of the same bundle and by the workers of one host, which take turns by a
// file lock), and one loaded RenderJob per job, shared by all of the job's chains on this worker.
#include <functional>
#include <future>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "worker/chain_source.h"

namespace farm {

class SceneCache {
 public:
  // Downloads bundle `hash` into the (new, empty) directory `dir`, checking every file's hash;
  // throws on failure.
  using BundleFetcher = std::function<void(const std::string& hash, const std::string& dir)>;

  SceneCache(std::string cacheDir, BundleFetcher fetch, size_t maxJobs = 4);

  // The job's renderer; fetches the bundle and loads the scene on first use. Concurrent calls
  // for one job load it once. Throws what loading threw.
  std::shared_ptr<const RenderJob> renderJob(const LeasedChain& chain);
  // The bundle's directory, fetching it if it is not cached yet.
  std::string bundleDir(const std::string& hash);

 private:
  std::shared_ptr<const RenderJob> load(const LeasedChain& chain);

  const std::string cacheDir_;
  const BundleFetcher fetch_;
  const size_t maxJobs_;
  std::mutex mutex_, fetchMutex_;
  std::map<std::string, std::shared_future<std::shared_ptr<const RenderJob>>> jobs_;
  std::list<std::string> recent_;  // job ids, most recently used first
};

}  // namespace farm
