#include "worker/worker_pool.h"

#include <algorithm>
#include <chrono>

namespace farm {

using Clock = std::chrono::steady_clock;

namespace {
Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}
std::string chainName(const LeasedChain& c) {
  return "chain " + std::to_string(c.spec.chainIndex) + " of " + c.jobId;
}
}  // namespace

WorkerPool::WorkerPool(ChainSource* source, WorkerPoolOptions options)
    : source_(source), options_(std::move(options)) {}

WorkerPool::~WorkerPool() {
  stop();
  for (auto& task : tasks_) {
    if (task->thread.joinable()) task->thread.join();
  }
}

void WorkerPool::log(const std::string& line) const {
  if (options_.log) options_.log(line);
}

void WorkerPool::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  source_->interrupt();  // run() may be waiting at the source for work
}

WorkerPoolStats WorkerPool::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void WorkerPool::runTask(Task* task) {
  const LeasedChain& chain = task->chain;
  bool failed = false;
  const Clock::time_point started = Clock::now();
  try {
    std::shared_ptr<const RenderJob> job = source_->renderJob(chain);
    job->runChain(
        chain.spec,
        [&](ChainFlush&& flush) {
          const int64_t work = flush.mutations;
          const Clock::time_point sending = Clock::now();
          FlushReceipt receipt = source_->upload(chain, std::move(flush));
          {
            std::lock_guard<std::mutex> lock(mutex_);
            stats_.uploadSeconds += std::chrono::duration<double>(Clock::now() - sending).count();
            if (receipt.accepted) {
              ++stats_.flushesAccepted;
              stats_.work += work;
            }
            if (receipt.duplicate) ++stats_.flushesDuplicate;
          }
          if (receipt.stop) {
            if (!receipt.yielded) log(chainName(chain) + " stops: " + receipt.reason);
            return false;
          }
          return !task->stop.load();
        },
        &task->stop);
  } catch (const std::exception& e) {
    failed = true;
    log(chainName(chain) + " failed: " + e.what());
  }
  source_->release(chain);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (failed) ++stats_.chainsFailed;
    stats_.chainSeconds += std::chrono::duration<double>(Clock::now() - started).count();
    task->done = true;
  }
  wake_.notify_all();
}

void WorkerPool::run() {
  double backoff = 0;
  Clock::time_point nextLease = Clock::now();
  Clock::time_point nextRenew = Clock::now() + seconds(source_->renewIntervalSeconds());
  std::string refused;
  int64_t failuresSeen = 0;
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stopping_) {
    // Reap chains that ended; a failed chain makes the next lease wait (the failure may repeat).
    for (auto it = tasks_.begin(); it != tasks_.end();) {
      if ((*it)->done) {
        lock.unlock();
        (*it)->thread.join();
        lock.lock();
        it = tasks_.erase(it);
      } else {
        ++it;
      }
    }
    if (stats_.chainsFailed > failuresSeen) {
      failuresSeen = stats_.chainsFailed;
      nextLease = std::max(nextLease, Clock::now() + seconds(1));
    }
    const int running = int(tasks_.size());
    const auto now = Clock::now();

    if (running < options_.threads && now >= nextLease) {
      lock.unlock();
      std::vector<LeasedChain> leases;
      const auto asked = Clock::now();
      try {
        leases = source_->lease(options_.threads - running,
                                running == 0 ? options_.leaseWaitSeconds : 0.0);
        if (backoff > 0) log("the coordinator is reachable again");
        backoff = 0;
        // Measured from the ask: after a wait that found nothing, ask again at once.
        nextLease = leases.empty() ? asked + seconds(options_.idleRetrySeconds) : Clock::now();
      } catch (const SourceRefused& e) {
        refused = e.what();
        lock.lock();
        break;
      } catch (const std::exception& e) {
        backoff = std::min(std::max(backoff * 2, 0.25), options_.maxBackoffSeconds);
        log(std::string(e.what()) + "; retrying in " + std::to_string(backoff).substr(0, 4) + " s");
        nextLease = Clock::now() + seconds(backoff);
      }
      lock.lock();
      for (LeasedChain& chain : leases) {
        // Named when it starts, so a log shows where every chain ran (and, after a failure,
        // how soon another worker took it up).
        log(chainName(chain) + " leased (epoch " + std::to_string(chain.epoch) +
            (chain.spec.resumeFlushIndex > 0
                 ? ", resuming at flush " + std::to_string(chain.spec.resumeFlushIndex)
                 : std::string(", from its seed")) +
            ")");
        auto task = std::make_unique<Task>();
        task->chain = std::move(chain);
        Task* raw = task.get();
        tasks_.push_back(std::move(task));
        ++stats_.chainsStarted;
        raw->thread = std::thread([this, raw] { runTask(raw); });
      }
      if (!leases.empty()) continue;
    }

    if (!tasks_.empty() && Clock::now() >= nextRenew) {
      std::vector<Task*> live;
      std::vector<const LeasedChain*> chains;
      for (auto& task : tasks_) {
        if (task->done) continue;
        live.push_back(task.get());
        chains.push_back(&task->chain);
      }
      lock.unlock();
      try {
        std::vector<bool> lost = source_->renew(chains);
        for (size_t i = 0; i < live.size() && i < lost.size(); ++i) {
          if (lost[i]) {
            log(chainName(live[i]->chain) + " lost its lease; stopping it");
            live[i]->stop = true;
          }
        }
      } catch (const std::exception& e) {
        log(std::string("cannot renew leases: ") + e.what());
      }
      lock.lock();
      nextRenew = Clock::now() + seconds(source_->renewIntervalSeconds());
    }

    // Sleep until a chain ends, stop() is called, or the next lease or renewal is due.
    Clock::time_point until = nextRenew;
    if (int(tasks_.size()) < options_.threads) until = std::min(until, nextLease);
    until = std::min(until, Clock::now() + std::chrono::milliseconds(500));
    wake_.wait_until(lock, until, [this] {
      if (stopping_) return true;
      for (auto& task : tasks_) {
        if (task->done) return true;
      }
      return false;
    });
  }
  // Stop every chain at its next flush and wait for them.
  for (auto& task : tasks_) task->stop = true;
  lock.unlock();
  for (auto& task : tasks_) {
    if (task->thread.joinable()) task->thread.join();
  }
  lock.lock();
  tasks_.clear();
  if (!refused.empty()) throw SourceRefused(refused);
}

}  // namespace farm
