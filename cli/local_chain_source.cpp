#include "cli/local_chain_source.h"

namespace farm {

LocalChainSource::LocalChainSource(Coordinator* coordinator, int threads)
    : coordinator_(coordinator) {
  WorkerInfo info;
  info.version = "embedded";
  info.host = "localhost";
  info.threads = threads;
  for (Algorithm a : allAlgorithms()) info.capabilities.insert(a);
  Status s = coordinator_->registerWorker(info, &workerId_);
  if (!s.isOk()) throw SourceRefused(s.message());
}

std::vector<LeasedChain> LocalChainSource::lease(int max, double waitSeconds) {
  std::vector<WorkerLease> leases;
  const auto wait = interrupted_ ? SteadyClock::duration::zero()
                                 : std::chrono::duration_cast<SteadyClock::duration>(
                                       std::chrono::duration<double>(waitSeconds));
  Status s = coordinator_->leaseChains(workerId_, max, &leases, wait,
                                       [this] { return interrupted_.load(); });
  if (!s.isOk()) throw SourceRefused(s.message());
  std::vector<LeasedChain> chains;
  for (WorkerLease& w : leases) {
    LeasedChain chain;
    chain.jobId = w.jobId;
    chain.spec = std::move(w.lease.spec);
    chain.epoch = w.lease.epoch;
    chain.settings = w.settings;
    chains.push_back(std::move(chain));
  }
  return chains;
}

void LocalChainSource::interrupt() {
  interrupted_ = true;
  coordinator_->wakeLeaseWaiters();
}

std::shared_ptr<const RenderJob> LocalChainSource::renderJob(const LeasedChain& chain) {
  auto job = coordinator_->renderJob(chain.jobId);
  if (!job) throw std::runtime_error("job " + chain.jobId + " has no scene loaded");
  return job;
}

FlushReceipt LocalChainSource::upload(const LeasedChain& chain, ChainFlush&& flush) {
  FlushAck ack;
  Status s = coordinator_->acceptFlush(workerId_, chain.jobId, chain.epoch, std::move(flush), &ack);
  if (!s.isOk()) throw std::runtime_error(s.message());
  FlushReceipt receipt;
  receipt.accepted = ack.result == FlushAck::Result::kAccepted;
  receipt.duplicate = ack.result == FlushAck::Result::kDuplicate;
  receipt.stop = ack.stop || ack.result == FlushAck::Result::kDiscarded;
  receipt.reason = ack.reason;
  receipt.yielded = ack.yielded;
  return receipt;
}

std::vector<bool> LocalChainSource::renew(const std::vector<const LeasedChain*>& chains) {
  std::vector<LeaseRef> refs, lost;
  for (const LeasedChain* c : chains) refs.push_back({c->jobId, c->spec.chainIndex, c->epoch});
  Status s = coordinator_->renewLeases(workerId_, refs, &lost);
  if (!s.isOk()) throw SourceUnavailable(s.message());
  std::vector<bool> result(chains.size(), false);
  for (const LeaseRef& r : lost) {
    for (size_t i = 0; i < chains.size(); ++i) {
      if (refs[i].jobId == r.jobId && refs[i].chain == r.chain && refs[i].epoch == r.epoch) {
        result[i] = true;
      }
    }
  }
  return result;
}

double LocalChainSource::renewIntervalSeconds() const {
  return std::max(0.2, coordinator_->leaseSeconds() / 3);
}

}  // namespace farm
