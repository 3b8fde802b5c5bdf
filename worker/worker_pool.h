#pragma once
// Runs leased chains, each on a thread of its own, up to a thread count: leases more when a
// chain ends, renews the leases of running chains, uploads every flush and stops a chain when
// the coordinator says so. Backs off while the source is unreachable.
#include <atomic>
#include <condition_variable>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "worker/chain_source.h"

namespace farm {

struct WorkerPoolOptions {
  int threads = 1;                 // chains run at once
  double idleRetrySeconds = 0.25;  // between asks when the source had no work
  // An idle pool's ask waits this long at the source for work to appear (and gets it the
  // moment it does); a busy pool asks without waiting, since it must also renew its leases.
  double leaseWaitSeconds = 1;
  double maxBackoffSeconds = 5;                 // longest wait while the source is unreachable
  std::function<void(const std::string&)> log;  // progress and trouble, one line each
};

struct WorkerPoolStats {
  int64_t chainsStarted = 0, chainsFailed = 0;
  int64_t flushesAccepted = 0, flushesDuplicate = 0;
  int64_t work = 0;  // mutations or samples in accepted flushes
  // Chain threads' time, and of it the time spent handing flushes over (encoding, uploading,
  // waiting for the answer): the chain renders nothing meanwhile.
  double chainSeconds = 0, uploadSeconds = 0;
};

class WorkerPool {
 public:
  WorkerPool(ChainSource* source, WorkerPoolOptions options);
  ~WorkerPool();

  // Works until stop() is called. Throws SourceRefused (after stopping its chains) when the
  // source refuses this worker.
  void run();
  // Asks run() to return: running chains stop at their next flush (which is still uploaded).
  void stop();
  WorkerPoolStats stats() const;

 private:
  struct Task {
    LeasedChain chain;
    std::atomic<bool> stop{false};
    std::atomic<bool> done{false};
    std::thread thread;
  };
  void runTask(Task* task);
  void log(const std::string& line) const;

  ChainSource* source_;
  const WorkerPoolOptions options_;
  std::list<std::unique_ptr<Task>> tasks_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  WorkerPoolStats stats_;
};

}  // namespace farm
