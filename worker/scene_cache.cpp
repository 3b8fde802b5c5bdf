#include "worker/scene_cache.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "proto/bundle_manifest.h"
#include "proto/sha256.h"

namespace farm {
namespace fs = std::filesystem;

namespace {

// An exclusive flock(2) on a file beside the bundle, held while one process of the host fetches
// it: workers sharing a cache directory (one host) fetch each bundle once, the others wait and
// find it complete. Released when the process dies, so a crashed fetch blocks nobody.
class FetchLock {
 public:
  explicit FetchLock(const fs::path& path) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw std::runtime_error("cannot open " + path.string() + ": " + strerror(errno));
    while (::flock(fd_, LOCK_EX) != 0) {
      if (errno != EINTR) {
        const std::string why = strerror(errno);
        ::close(fd_);
        throw std::runtime_error("cannot lock " + path.string() + ": " + why);
      }
    }
  }
  ~FetchLock() { ::close(fd_); }  // closing the descriptor releases the lock
  FetchLock(const FetchLock&) = delete;
  FetchLock& operator=(const FetchLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace

SceneCache::SceneCache(std::string cacheDir, BundleFetcher fetch, size_t maxJobs)
    : cacheDir_(std::move(cacheDir)),
      fetch_(std::move(fetch)),
      maxJobs_(std::max<size_t>(1, maxJobs)) {}

std::string SceneCache::bundleDir(const std::string& hash) {
  if (!isSha256Hex(hash)) throw std::runtime_error("malformed bundle hash '" + hash + "'");
  const fs::path dir = fs::path(cacheDir_) / hash;
  // Complete bundles carry a marker beside them; a directory without one is a broken download.
  const fs::path marker = fs::path(cacheDir_) / (hash + ".complete");
  std::lock_guard<std::mutex> lock(fetchMutex_);
  std::error_code ec;
  if (fs::exists(marker, ec) && fs::is_directory(dir, ec)) return dir.string();
  fs::create_directories(cacheDir_, ec);
  if (ec)
    throw std::runtime_error("cannot create cache directory " + cacheDir_ + ": " + ec.message());
  FetchLock hostLock(fs::path(cacheDir_) / (hash + ".lock"));
  // Another worker of this host may have fetched it while this one waited for the lock.
  if (fs::exists(marker, ec) && fs::is_directory(dir, ec)) return dir.string();
  // Download beside the final place and rename: other workers sharing the cache directory never
  // see a half-written bundle.
  const fs::path temp =
      fs::path(cacheDir_) / (hash + ".partial-" + std::to_string(std::random_device{}()));
  fs::remove_all(temp, ec);
  fs::create_directories(temp);
  try {
    fetch_(hash, temp.string());
  } catch (...) {
    fs::remove_all(temp, ec);
    throw;
  }
  fs::remove_all(dir, ec);
  fs::rename(temp, dir, ec);
  if (ec) {
    fs::remove_all(temp, ec);
    if (!fs::exists(marker, ec)) {
      throw std::runtime_error("cannot move the bundle into " + dir.string());
    }
  }
  std::ofstream(marker) << hash << "\n";
  return dir.string();
}

std::shared_ptr<const RenderJob> SceneCache::load(const LeasedChain& chain) {
  std::string problem = checkRelativePath(chain.scenePath);
  if (!problem.empty()) throw std::runtime_error("bad scene path in lease: " + problem);
  const std::string root = bundleDir(chain.bundleHash);
  std::shared_ptr<Scene> scene = loadScene(root + "/" + chain.scenePath, chain.settings);
  return std::make_shared<RenderJob>(scene, chain.settings, chain.jobId);
}

std::shared_ptr<const RenderJob> SceneCache::renderJob(const LeasedChain& chain) {
  std::promise<std::shared_ptr<const RenderJob>> promise;
  std::shared_future<std::shared_ptr<const RenderJob>> future;
  bool loader = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    recent_.remove(chain.jobId);
    recent_.push_front(chain.jobId);
    auto it = jobs_.find(chain.jobId);
    if (it != jobs_.end()) {
      future = it->second;
    } else {
      future = promise.get_future().share();
      jobs_[chain.jobId] = future;
      loader = true;
      // Forget the least recently used jobs (chains still running keep theirs alive).
      while (recent_.size() > maxJobs_) {
        jobs_.erase(recent_.back());
        recent_.pop_back();
      }
    }
  }
  if (loader) {
    try {
      promise.set_value(load(chain));
    } catch (...) {
      promise.set_exception(std::current_exception());
      std::lock_guard<std::mutex> lock(mutex_);
      jobs_.erase(chain.jobId);  // the next lease tries again
    }
  }
  return future.get();
}

}  // namespace farm
