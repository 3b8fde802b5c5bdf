#pragma once
// Where a worker's chains come from and where their flushes go. A farm-worker talks to a remote
// coordinator (RemoteChainSource); the embedded `farm render` hands the in-process coordinator
// to the same WorkerPool, so both run chains the same way.
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/render/render_job.h"

namespace farm {

struct LeasedChain {
  std::string jobId;
  ChainSpec spec;
  uint64_t epoch = 0;       // lease generation, echoed with every flush
  std::string bundleHash;   // the scene bundle (empty: the source knows the scene itself)
  std::string scenePath;    // the scene file inside the bundle
  RenderSettings settings;  // the job's settings (loadScene applies the film size)
};

struct FlushReceipt {
  bool accepted = false;   // added to the image now
  bool duplicate = false;  // was added before (a retried upload)
  bool stop = false;       // the chain should stop
  std::string reason;      // why it should stop
  bool yielded = false;    // stopped only to let waiting chains run: nothing to report
};

// The source cannot be reached now; the caller backs off and tries again.
class SourceUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The worker cannot work with this source at all (e.g. incompatible protocol versions).
class SourceRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ChainSource {
 public:
  virtual ~ChainSource() = default;
  // Up to `max` chains to run now; empty when there is no work at the moment. With
  // `waitSeconds` > 0 the source may hold the call that long for work to appear and answer as
  // soon as it does (a source that cannot wait answers at once). Throws SourceUnavailable or
  // SourceRefused.
  virtual std::vector<LeasedChain> lease(int max, double waitSeconds) = 0;
  // Ends a lease() wait in progress (it returns no chains) and makes later ones answer at once:
  // the pool is stopping. May be called from any thread.
  virtual void interrupt() {}
  // The renderer's job for a leased chain (loads the scene on first use). Throws on failure.
  virtual std::shared_ptr<const RenderJob> renderJob(const LeasedChain& chain) = 0;
  // Delivers one flush (retrying what can be retried). Throws when it cannot be delivered: the
  // chain then stops, its lease expires, and the chain resumes elsewhere from the last flush
  // that was delivered.
  virtual FlushReceipt upload(const LeasedChain& chain, ChainFlush&& flush) = 0;
  // The chain's thread is done with it (it finished, stopped or failed).
  virtual void release(const LeasedChain& chain) { (void)chain; }
  // Keeps the leases of running chains alive; returns, per chain, whether its lease was lost.
  // Throws SourceUnavailable.
  virtual std::vector<bool> renew(const std::vector<const LeasedChain*>& chains) = 0;
  // How often renew() should run.
  virtual double renewIntervalSeconds() const = 0;
};

}  // namespace farm
