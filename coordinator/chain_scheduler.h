#pragma once
// Hands a job's chains to workers under leases. A lease lives for a fixed time unless its holder
// renews it (an accepted flush or a renewal does); an expired lease puts the chain back in the
// queue, and whoever leases it next resumes from the last accepted flush's state, so a worker
// that dies costs at most one flush interval (docs/design.md, "The work unit").
#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/chain/chain_spec.h"

namespace farm {

using SteadyClock = std::chrono::steady_clock;

struct ChainLease {
  ChainSpec spec;      // with the resume fields filled in from the last accepted flush
  uint64_t epoch = 0;  // lease generation of this chain: an upload names the lease it ran under
  SteadyClock::time_point deadline;
};

class ChainScheduler {
 public:
  // A chain's resume point: what a durable coordinator checkpoints (coordinator/job_store.h).
  struct ChainSnapshot {
    std::string resumeState;
    int64_t mutationsDone = 0;
    uint32_t nextFlushIndex = 0;
    bool finished = false;
  };

  // Epochs of the chains' leases start after `firstEpoch`: a coordinator that restarts passes a
  // base above any epoch it handed out before, so that no lease of the new run can be mistaken
  // for one of the old.
  ChainScheduler(std::vector<ChainSpec> chains, SteadyClock::duration leaseDuration,
                 uint64_t firstEpoch = 0);

  // Every chain's resume point, by index; and the way back (no chain leased, the finished ones
  // finished). `resume` holds one entry per chain.
  std::vector<ChainSnapshot> snapshot() const;
  void restore(const std::vector<ChainSnapshot>& resume);

  uint32_t chainCount() const { return uint32_t(chains_.size()); }
  bool hasChain(uint32_t chain) const { return chain < chains_.size(); }

  // Leases up to `max` waiting chains to `worker`: those with the least work done first (then
  // the lowest index), so that time-sliced chains advance evenly.
  std::vector<ChainLease> lease(const std::string& worker, int max, SteadyClock::time_point now);
  // True when `worker` holds the chain's current lease `epoch`.
  bool holds(const std::string& worker, uint32_t chain, uint64_t epoch) const;
  // Extends a lease its holder still has; false when the lease is gone (expired, moved, done).
  bool renew(const std::string& worker, uint32_t chain, uint64_t epoch,
             SteadyClock::time_point now);

  // An accepted flush: the chain's new resume point. A flush marked finished ends the chain.
  // Extends the lease when (worker, epoch) holds it.
  void recordFlush(uint32_t chain, uint32_t flushIndex, int64_t mutations, std::string state,
                   bool finished, const std::string& worker, uint64_t epoch,
                   SteadyClock::time_point now);
  // Ends a chain early (the job's time budget is spent and the chain was told to stop).
  void finishChain(uint32_t chain);
  // Takes a chain back from its holder (who was told to stop it) and queues it again; the next
  // lease resumes it from its last accepted flush. How chains without a budget (time-limited
  // jobs) share fewer threads than there are chains.
  void yieldChain(uint32_t chain);

  // Puts chains whose lease expired back in the queue (or, once stopping, ends them). Returns
  // the number of leases that expired; `expired` (if given) receives each one's chain and holder.
  int expireLeases(SteadyClock::time_point now,
                   std::vector<std::pair<uint32_t, std::string>>* expired = nullptr);

  // No more leases: waiting chains end now, leased ones at their next flush or lease expiry.
  void stop();
  bool stopping() const { return stopping_; }

  bool allFinished() const { return finished_ == chains_.size(); }
  uint32_t finishedCount() const { return uint32_t(finished_); }
  uint32_t leasedCount() const;
  // Distinct workers holding a lease of one of the chains.
  uint32_t holderCount() const;
  // Leases held, by worker.
  std::map<std::string, uint32_t> holders() const;
  uint32_t waitingCount() const;
  // Mutations (or samples) accepted from the chain so far.
  int64_t chainMutations(uint32_t chain) const { return chains_.at(chain).mutationsDone; }

 private:
  enum class State { kWaiting, kLeased, kFinished };
  struct Chain {
    ChainSpec spec;
    State state = State::kWaiting;
    std::string holder;
    uint64_t epoch = 0;
    SteadyClock::time_point deadline;
    // Resume point: the state after the last accepted flush.
    std::string resumeState;
    int64_t mutationsDone = 0;
    uint32_t nextFlushIndex = 0;
  };
  void finish(Chain& chain);

  std::vector<Chain> chains_;
  SteadyClock::duration leaseDuration_;
  size_t finished_ = 0;
  bool stopping_ = false;
};

}  // namespace farm
