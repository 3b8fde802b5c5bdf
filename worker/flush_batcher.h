#pragma once
// Sums the flushes of the chains a worker runs for one job into one upload (issue 8, part 4):
// the coordinator's ingest is bounded by bytes and flushes a second, and a worker's chains of
// one job flush at about the same moments, so one summed film in place of N cuts both by N.
//
// A chain's thread hands its flush to upload() and waits for the answer, as it waits for a
// single upload (a chain has at most one flush unanswered, so a batch holds at most one flush
// a chain). The batch goes out when every chain of the job this worker runs has a flush in it,
// or when its first flush has waited long enough, whichever is first: `windowSeconds`, and at
// most kWaitShare of the time that chain took to render its flush (for a chain's first flush,
// the last time any chain of the job took): a waiting chain's thread is idle, so the wait is
// bounded by a share of the work. The thread that finds the batch due
// sends it and hands every waiting thread its answer. Chains answered together start their next
// interval together, so they stay in step as far as their intervals' lengths agree.
// Transport-free: `send` does the sending, so that the pool's tests can drive it without a
// network.
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "worker/chain_source.h"

namespace farm {

struct BatchItem {
  const LeasedChain* chain = nullptr;
  ChainFlush flush;
};

// What became of one flush of a batch.
struct BatchAnswer {
  enum class Kind {
    kReceipt,  // counted, a duplicate, or discarded: `receipt` says which
    kResend,   // sound but not counted (another flush held the batch back): send it again
    kError,    // cannot be delivered (`error` says why): the chain stops
  };
  Kind kind = Kind::kError;
  FlushReceipt receipt;
  std::string error;
};

class FlushBatcher {
 public:
  // The most a flush waits for its peers, as a share of the time its chain took to render it.
  static constexpr double kWaitShare = 0.05;

  // Sends one batch of flushes of one job; returns one answer per item, in order. May throw:
  // every item then gets the exception's message as its error.
  using Send = std::function<std::vector<BatchAnswer>(const std::vector<BatchItem*>& items)>;

  FlushBatcher(double windowSeconds, Send send);

  // A batch holds flushes of one job's chains of one error group (ChainSpec::errorGroup): the
  // coordinator sums each group apart. This is its queue's key.
  static std::string key(const std::string& jobId, uint32_t errorGroup);
  static std::string key(const LeasedChain& chain) {
    return key(chain.jobId, chain.spec.errorGroup);
  }

  // A chain of the queue `key` started or ended on this worker: a batch is full when it holds a
  // flush of every chain the worker runs for its job and group.
  void chainStarted(const std::string& key);
  void chainEnded(const std::string& key);

  // Blocks until the flush has been sent (in some batch) and answered; throws
  // std::runtime_error when it cannot be delivered.
  FlushReceipt upload(const LeasedChain& chain, ChainFlush&& flush);

  struct Stats {
    int64_t batches = 0;  // uploads sent
    int64_t flushes = 0;  // flushes in them (resent ones once per sending)
  };
  Stats stats() const;

 private:
  using Clock = std::chrono::steady_clock;
  struct Waiting {
    BatchItem item;
    bool done = false;
    BatchAnswer answer;
  };
  struct JobQueue {
    std::vector<Waiting*> pending;  // in arrival order
    Clock::time_point due;          // when the oldest pending flush has waited long enough
    int running = 0;                // chains of the job this worker runs
    bool sending = false;
    std::map<uint32_t, Clock::time_point> answered;  // per chain: its last flush's answer
    Clock::duration interval{};                      // the last a chain took between flushes
  };

  const Clock::duration window_;
  const Send send_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::string, JobQueue> jobs_;
  Stats stats_;
};

}  // namespace farm
