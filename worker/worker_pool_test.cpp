// The worker's pool against a scripted ChainSource: every flush is delivered once, a chain whose
// upload fails stops without taking the pool down, a stop from the coordinator ends the chain,
// and a refusing source ends run() with the refusal.
#include "worker/worker_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <thread>

#include "tests/test_support.h"
#include "worker/scene_cache.h"

namespace farm {
namespace {

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

class ScriptedSource : public ChainSource {
 public:
  explicit ScriptedSource(int chains) {
    RenderSettings settings;
    settings.algorithm = Algorithm::PathTracing;
    settings.width = 8;
    settings.height = 8;
    settings.samplesPerPixel = 64 * chains;  // 4096 samples per chain: 4 flushes of 1024
    settings.numChains = chains;
    job_ = std::make_shared<RenderJob>(loadScene(kScene, settings), settings, "job-scripted");
    for (ChainSpec& spec : job_->planChains(job_->bootstrap())) {
      spec.flushInterval = 1024;
      LeasedChain chain;
      chain.jobId = "job-scripted";
      chain.spec = spec;
      chain.epoch = 1;
      chain.settings = settings;
      waiting_.push_back(chain);
    }
  }

  std::vector<LeasedChain> lease(int max, double waitSeconds) override {
    std::lock_guard<std::mutex> lock(mutex_);
    asks_.emplace_back(running_, waitSeconds);
    if (refuse_) throw SourceRefused("protocol mismatch (scripted)");
    if (unavailableLeft_ > 0) {
      --unavailableLeft_;
      throw SourceUnavailable("coordinator down (scripted)");
    }
    std::vector<LeasedChain> out;
    while (int(out.size()) < max && !waiting_.empty()) {
      out.push_back(waiting_.back());
      waiting_.pop_back();
    }
    maxConcurrent_ = std::max(maxConcurrent_, running_ += int(out.size()));
    return out;
  }
  std::shared_ptr<const RenderJob> renderJob(const LeasedChain&) override { return job_; }
  FlushReceipt upload(const LeasedChain& chain, ChainFlush&& flush) override {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto key = std::make_pair(chain.spec.chainIndex, flush.flushIndex);
    EXPECT_TRUE(delivered_.insert(key).second) << "flush delivered twice";
    if (flush.finished) --running_;
    if (chain.spec.chainIndex == failChain_) {
      --running_;
      throw std::runtime_error("upload failed (scripted)");
    }
    FlushReceipt receipt;
    receipt.accepted = true;
    receipt.stop = chain.spec.chainIndex == stopChain_;
    if (receipt.stop) --running_;
    return receipt;
  }
  std::vector<bool> renew(const std::vector<const LeasedChain*>& chains) override {
    return std::vector<bool>(chains.size(), false);
  }
  double renewIntervalSeconds() const override { return 0.05; }

  std::mutex mutex_;
  std::shared_ptr<RenderJob> job_;
  std::vector<LeasedChain> waiting_;
  std::set<std::pair<uint32_t, uint32_t>> delivered_;
  uint32_t failChain_ = 999, stopChain_ = 999;
  int unavailableLeft_ = 0;
  bool refuse_ = false;
  int running_ = 0, maxConcurrent_ = 0;
  std::vector<std::pair<int, double>> asks_;  // (chains running, wait) at each lease
};

void runUntil(WorkerPool& pool, ScriptedSource& source, size_t flushes) {
  std::thread runner([&] { pool.run(); });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(source.mutex_);
      if (source.delivered_.size() >= flushes && source.waiting_.empty()) break;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      ADD_FAILURE() << "timed out";
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  pool.stop();
  runner.join();
}

TEST(WorkerPool, RunsEveryChainWithinItsThreadCount) {
  ScriptedSource source(6);
  WorkerPoolOptions options;
  options.threads = 2;
  options.idleRetrySeconds = 0.01;
  source.unavailableLeft_ = 2;  // the pool backs off and tries again
  options.maxBackoffSeconds = 0.05;
  WorkerPool pool(&source, options);
  runUntil(pool, source, 6 * 4);
  EXPECT_EQ(source.delivered_.size(), 24u);
  EXPECT_LE(source.maxConcurrent_, 2);
  EXPECT_EQ(pool.stats().chainsStarted, 6);
  EXPECT_EQ(pool.stats().flushesAccepted, 24);
  EXPECT_EQ(pool.stats().work, 6 * 4096);
  // Idle, the pool waits at the source for work; with chains running it must not (their leases
  // need renewing).
  ASSERT_FALSE(source.asks_.empty());
  EXPECT_EQ(source.asks_.front().second, options.leaseWaitSeconds);
  for (const auto& [running, wait] : source.asks_) {
    if (running > 0) {
      EXPECT_EQ(wait, 0.0) << "asked with a wait while " << running << " ran";
    }
  }
}

TEST(WorkerPool, FailedUploadAndStopEndOnlyTheirChain) {
  ScriptedSource source(4);
  source.failChain_ = 1;
  source.stopChain_ = 2;
  WorkerPoolOptions options;
  options.threads = 4;
  WorkerPool pool(&source, options);
  runUntil(pool, source, 4 + 4 + 1 + 1);
  std::lock_guard<std::mutex> lock(source.mutex_);
  EXPECT_EQ(source.delivered_.count({1, 1}), 0u) << "a failed chain must not go on";
  EXPECT_EQ(source.delivered_.count({2, 1}), 0u) << "a stopped chain must not go on";
  EXPECT_EQ(source.delivered_.count({0, 3}), 1u);
  EXPECT_EQ(source.delivered_.count({3, 3}), 1u);
  EXPECT_EQ(pool.stats().chainsFailed, 1);
}

TEST(WorkerPool, RefusalEndsRun) {
  ScriptedSource source(1);
  source.refuse_ = true;
  WorkerPool pool(&source, WorkerPoolOptions{});
  EXPECT_THROW(pool.run(), SourceRefused);
}

// Workers of one host share its cache directory and fetch each bundle once: two caches on one
// directory (two processes' worth: flock locks are per open file) asked for the same bundle at
// once fetch it once, and the second finds it complete.
TEST(SceneCache, WorkersOfOneHostFetchABundleOnce) {
  testing::ScratchDir scratch("scene-cache");
  std::atomic<int> fetches{0};
  auto fetcher = [&](const std::string&, const std::string& dir) {
    ++fetches;
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // a slow download
    std::ofstream(dir + "/scene.xml") << "<scene/>";
  };
  SceneCache a(scratch.path(), fetcher), b(scratch.path(), fetcher);
  const std::string hash(64, 'a');
  std::string dirA, dirB;
  std::thread other([&] { dirB = b.bundleDir(hash); });
  dirA = a.bundleDir(hash);
  other.join();
  EXPECT_EQ(fetches.load(), 1);
  EXPECT_EQ(dirA, dirB);
  EXPECT_TRUE(std::filesystem::exists(dirA + "/scene.xml"));
}

}  // namespace
}  // namespace farm
