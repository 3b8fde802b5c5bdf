#pragma once
// A ChainSource on the far side of gRPC: registers with a farm-coordinator, leases chains,
// fetches scene bundles into a SceneCache, uploads flushes in checksummed chunks and renews
// leases. Retries what can be retried; every call has a deadline. gRPC stays in the .cpp.
#include <functional>
#include <memory>
#include <string>

#include "proto/transport_security.h"
#include "worker/chain_source.h"
#include "worker/flush_batcher.h"

namespace farm {

struct RemoteSourceOptions {
  std::string coordinator;  // HOST:PORT
  ClientSecurity security;  // TLS roots, client certificate and work token to present
  int threads = 1;          // announced at registration
  std::string cacheDir;     // scene bundles, by content hash
  std::string version = "farm-worker";
  double uploadRetrySeconds = 60;  // give up delivering a flush after this long
  // > 0: the flushes of this worker's chains of one job go as one summed upload, sent when
  // every such chain has flushed or this long after the first did (worker/flush_batcher.h);
  // 0: each flush on its own.
  double batchWindowSeconds = 0;
  std::function<void(const std::string&)> log;
};

class RemoteChainSource final : public ChainSource {
 public:
  // Throws std::invalid_argument, naming the file, when a TLS or token file cannot be used.
  explicit RemoteChainSource(RemoteSourceOptions options);
  ~RemoteChainSource() override;

  // From one thread at a time (WorkerPool's loop): the pixel allocations a request says it holds
  // must still be held when its answer is read.
  std::vector<LeasedChain> lease(int max, double waitSeconds) override;
  void interrupt() override;
  std::shared_ptr<const RenderJob> renderJob(const LeasedChain& chain) override;
  FlushReceipt upload(const LeasedChain& chain, ChainFlush&& flush) override;
  void release(const LeasedChain& chain) override;
  // Uploads sent and flushes in them, with a batch window (zeros without).
  FlushBatcher::Stats batchStats() const;
  // Leases that brought a pixel allocation's bytes: a job's once while it is among the last
  // kMaxHeldAllocations (proto/wire_limits.h) this worker used.
  int allocationsReceived() const;
  std::vector<bool> renew(const std::vector<const LeasedChain*>& chains) override;
  double renewIntervalSeconds() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace farm
