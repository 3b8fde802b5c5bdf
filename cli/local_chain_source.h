#pragma once
// A ChainSource over the in-process coordinator: `farm render` runs the same WorkerPool as
// farm-worker, but leases, flushes and renewals are function calls and the scene is the one the
// coordinator loaded (no bundle, no second load).
#include <atomic>
#include <string>

#include "coordinator/coordinator.h"
#include "worker/chain_source.h"

namespace farm {

class LocalChainSource final : public ChainSource {
 public:
  // Registers a worker with `threads` threads; throws if the coordinator refuses.
  LocalChainSource(Coordinator* coordinator, int threads);

  std::vector<LeasedChain> lease(int max, double waitSeconds) override;
  void interrupt() override;
  std::shared_ptr<const RenderJob> renderJob(const LeasedChain& chain) override;
  FlushReceipt upload(const LeasedChain& chain, ChainFlush&& flush) override;
  std::vector<bool> renew(const std::vector<const LeasedChain*>& chains) override;
  double renewIntervalSeconds() const override;

 private:
  Coordinator* coordinator_;
  std::string workerId_;
  std::atomic<bool> interrupted_{false};
};

}  // namespace farm
