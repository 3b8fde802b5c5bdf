#include "coordinator/chain_scheduler.h"

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

namespace farm {

ChainScheduler::ChainScheduler(std::vector<ChainSpec> chains, SteadyClock::duration leaseDuration,
                               uint64_t firstEpoch)
    : leaseDuration_(leaseDuration) {
  chains_.reserve(chains.size());
  for (ChainSpec& spec : chains) {
    Chain chain;
    chain.epoch = firstEpoch;
    // A plan may come with resume fields set (never today); honour them as the starting point.
    chain.resumeState = spec.resumeState;
    chain.mutationsDone = spec.resumeMutations;
    chain.nextFlushIndex = spec.resumeFlushIndex;
    chain.spec = std::move(spec);
    chains_.push_back(std::move(chain));
  }
}

std::vector<ChainScheduler::ChainSnapshot> ChainScheduler::snapshot() const {
  std::vector<ChainSnapshot> out;
  out.reserve(chains_.size());
  for (const Chain& c : chains_) {
    out.push_back({c.resumeState, c.mutationsDone, c.nextFlushIndex, c.state == State::kFinished});
  }
  return out;
}

void ChainScheduler::restore(const std::vector<ChainSnapshot>& resume) {
  if (resume.size() != chains_.size()) {
    throw std::invalid_argument("a resume record of " + std::to_string(resume.size()) +
                                " chains for a plan of " + std::to_string(chains_.size()));
  }
  finished_ = 0;
  for (size_t i = 0; i < chains_.size(); ++i) {
    Chain& c = chains_[i];
    c.resumeState = resume[i].resumeState;
    c.mutationsDone = resume[i].mutationsDone;
    c.nextFlushIndex = resume[i].nextFlushIndex;
    c.holder.clear();
    c.state = resume[i].finished ? State::kFinished : State::kWaiting;
    finished_ += resume[i].finished;
  }
}

std::vector<ChainLease> ChainScheduler::lease(const std::string& worker, int max,
                                              SteadyClock::time_point now) {
  std::vector<ChainLease> leases;
  if (stopping_) return leases;
  std::vector<uint32_t> waiting;
  for (uint32_t i = 0; i < chains_.size(); ++i) {
    if (chains_[i].state == State::kWaiting) waiting.push_back(i);
  }
  std::stable_sort(waiting.begin(), waiting.end(), [&](uint32_t a, uint32_t b) {
    return chains_[a].mutationsDone < chains_[b].mutationsDone;
  });
  // Whole error groups to one worker where it can take them (its chains then go up in one
  // batch), and the group least served to the next ask: running chains first, then work done.
  // One worker of few threads so cycles through the groups, and every group has work to show
  // for the error estimate early in the job, not only once the groups before it are done.
  std::vector<uint32_t> order;
  order.reserve(waiting.size());
  std::vector<bool> taken(waiting.size(), false);
  std::map<uint32_t, std::pair<int64_t, int64_t>> served;  // group -> (running, work)
  for (const Chain& c : chains_) {
    auto& s = served[c.spec.errorGroup];
    s.first += c.state == State::kLeased;
    s.second += c.mutationsDone;
  }
  while (order.size() < waiting.size() && int(order.size()) < max) {
    std::optional<uint32_t> group;
    for (size_t k = 0; k < waiting.size(); ++k) {
      const uint32_t g = chains_[waiting[k]].spec.errorGroup;
      if (!taken[k] &&
          (!group || served[g] < served[*group] || (served[g] == served[*group] && g < *group)))
        group = g;
    }
    for (size_t k = 0; k < waiting.size() && int(order.size()) < max; ++k) {
      if (taken[k] || chains_[waiting[k]].spec.errorGroup != *group) continue;
      taken[k] = true;
      order.push_back(waiting[k]);
      ++served[*group].first;
    }
  }
  for (uint32_t index : order) {
    Chain& chain = chains_[index];
    chain.state = State::kLeased;
    chain.holder = worker;
    ++chain.epoch;
    chain.deadline = now + leaseDuration_;
    ChainLease lease;
    lease.spec = chain.spec;
    lease.spec.resumeState = chain.resumeState;
    lease.spec.resumeMutations = chain.mutationsDone;
    lease.spec.resumeFlushIndex = chain.nextFlushIndex;
    lease.epoch = chain.epoch;
    lease.deadline = chain.deadline;
    leases.push_back(std::move(lease));
  }
  return leases;
}

bool ChainScheduler::holds(const std::string& worker, uint32_t chain, uint64_t epoch) const {
  if (chain >= chains_.size()) return false;
  const Chain& c = chains_[chain];
  return c.state == State::kLeased && c.holder == worker && c.epoch == epoch;
}

bool ChainScheduler::renew(const std::string& worker, uint32_t chain, uint64_t epoch,
                           SteadyClock::time_point now) {
  if (!holds(worker, chain, epoch)) return false;
  chains_[chain].deadline = now + leaseDuration_;
  return true;
}

void ChainScheduler::recordFlush(uint32_t chain, uint32_t flushIndex, int64_t mutations,
                                 std::string state, bool finished, const std::string& worker,
                                 uint64_t epoch, SteadyClock::time_point now) {
  Chain& c = chains_.at(chain);
  c.resumeState = std::move(state);
  c.mutationsDone += mutations;
  c.nextFlushIndex = flushIndex + 1;
  if (finished) {
    finish(c);
  } else if (holds(worker, chain, epoch)) {
    c.deadline = now + leaseDuration_;
  }
}

void ChainScheduler::finishChain(uint32_t chain) {
  finish(chains_.at(chain));
}

void ChainScheduler::yieldChain(uint32_t chain) {
  Chain& c = chains_.at(chain);
  if (c.state != State::kLeased) return;
  c.state = State::kWaiting;
  c.holder.clear();
}

void ChainScheduler::finish(Chain& chain) {
  if (chain.state == State::kFinished) return;
  chain.state = State::kFinished;
  chain.holder.clear();
  ++finished_;
}

int ChainScheduler::expireLeases(SteadyClock::time_point now,
                                 std::vector<std::pair<uint32_t, std::string>>* holders) {
  int expired = 0;
  for (Chain& chain : chains_) {
    if (chain.state != State::kLeased || now < chain.deadline) continue;
    ++expired;
    if (holders) holders->emplace_back(uint32_t(&chain - chains_.data()), chain.holder);
    if (stopping_) {
      finish(chain);
    } else {
      chain.state = State::kWaiting;
      chain.holder.clear();
    }
  }
  return expired;
}

void ChainScheduler::stop() {
  stopping_ = true;
  for (Chain& chain : chains_) {
    if (chain.state == State::kWaiting) finish(chain);
  }
}

uint32_t ChainScheduler::leasedCount() const {
  uint32_t n = 0;
  for (const Chain& chain : chains_) n += chain.state == State::kLeased;
  return n;
}

uint32_t ChainScheduler::holderCount() const {
  return uint32_t(holders().size());
}

std::map<std::string, uint32_t> ChainScheduler::holders() const {
  std::map<std::string, uint32_t> held;
  for (const Chain& chain : chains_) {
    if (chain.state == State::kLeased) ++held[chain.holder];
  }
  return held;
}

uint32_t ChainScheduler::waitingCount() const {
  uint32_t n = 0;
  for (const Chain& chain : chains_) n += chain.state == State::kWaiting;
  return n;
}

}  // namespace farm
