#include "coordinator/splat_aggregator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace farm {

SplatAggregator::SplatAggregator(int width, int height, uint32_t numChains)
    : width_(width),
      height_(height),
      sums_(size_t(width) * size_t(height) * 3, 0.0),
      nextFlush_(numChains, 0) {}

SplatAggregator::SplatAggregator(int width, int height, Snapshot snapshot)
    : width_(width),
      height_(height),
      sums_(std::move(snapshot.sums)),
      nextFlush_(std::move(snapshot.nextFlush)),
      workDone_(snapshot.workDone),
      rejected_(snapshot.rejected),
      rays_(snapshot.rays),
      acceptedFlushes_(snapshot.acceptedFlushes),
      tallies_(std::move(snapshot.tallies)) {
  if (sums_.size() != size_t(width) * size_t(height) * 3) {
    throw std::invalid_argument("the snapshot's film holds " + std::to_string(sums_.size()) +
                                " values, not " + std::to_string(width) + "x" +
                                std::to_string(height) + "x3");
  }
}

SplatAggregator::Snapshot SplatAggregator::snapshot(bool withSums) const {
  Snapshot s;
  if (withSums) s.sums = sums_;
  s.nextFlush = nextFlush_;
  s.workDone = workDone_;
  s.rejected = rejected_;
  s.rays = rays_;
  s.acceptedFlushes = acceptedFlushes_;
  s.tallies = tallies_;
  return s;
}

FlushOutcome SplatAggregator::add(const ChainFlush& flush, std::string* problem) {
  const FlushOutcome outcome = check(flush, problem);
  if (outcome != FlushOutcome::kAccepted) return outcome;
  for (size_t i = 0; i < sums_.size(); ++i) sums_[i] += double(flush.splats[i]);
  countFlush(flush);
  return FlushOutcome::kAccepted;
}

FlushOutcome SplatAggregator::addBatch(const FlushBatch& batch, std::string* problem) {
  std::vector<bool> seen(nextFlush_.size(), false);
  for (const ChainFlush& entry : batch.entries) {
    const FlushOutcome outcome = checkEntry(entry, problem);
    if (outcome != FlushOutcome::kAccepted) return outcome;
    if (seen[entry.chainIndex]) {
      if (problem)
        *problem = "the batch holds two flushes of chain " + std::to_string(entry.chainIndex);
      return FlushOutcome::kOutOfOrder;
    }
    seen[entry.chainIndex] = true;
  }
  if (batch.entries.empty()) {
    if (problem) *problem = "the batch holds no flush";
    return FlushOutcome::kBadValues;
  }
  const FlushOutcome film = checkFilm(batch.film, "the batch's film", problem);
  if (film != FlushOutcome::kAccepted) return film;
  for (size_t i = 0; i < sums_.size(); ++i) sums_[i] += double(batch.film.splats[i]);
  for (const ChainFlush& entry : batch.entries) countFlush(entry);
  return FlushOutcome::kAccepted;
}

void SplatAggregator::countFlush(const ChainFlush& flush) {
  workDone_ += flush.mutations;
  rejected_ += flush.rejected;
  rays_ += flush.rays;
  for (const MutationTally& t : flush.tallies) {
    auto it = std::find_if(tallies_.begin(), tallies_.end(),
                           [&](const MutationTally& sum) { return sum.name == t.name; });
    if (it == tallies_.end()) {
      if (tallies_.size() >= kMaxTallyKinds) continue;  // a job tallies a handful of kinds
      it = tallies_.insert(tallies_.end(), MutationTally{t.name, 0, 0});
    }
    it->proposed += t.proposed;
    it->accepted += t.accepted;
  }
  ++acceptedFlushes_;
  ++nextFlush_[flush.chainIndex];
}

FlushOutcome SplatAggregator::check(const ChainFlush& flush, std::string* problem) const {
  const FlushOutcome outcome = checkEntry(flush, problem);
  if (outcome != FlushOutcome::kAccepted) return outcome;
  return checkFilm(
      flush,
      "flush " + std::to_string(flush.flushIndex) + " of chain " + std::to_string(flush.chainIndex),
      problem);
}

FlushOutcome SplatAggregator::checkEntry(const ChainFlush& flush, std::string* problem) const {
  std::string ignored;
  std::string& why = problem ? *problem : ignored;
  const std::string name =
      "flush " + std::to_string(flush.flushIndex) + " of chain " + std::to_string(flush.chainIndex);
  if (flush.chainIndex >= nextFlush_.size()) {
    why = "chain " + std::to_string(flush.chainIndex) + " does not exist (the job has " +
          std::to_string(nextFlush_.size()) + " chains)";
    return FlushOutcome::kUnknownChain;
  }
  const uint32_t next = nextFlush_[flush.chainIndex];
  if (flush.flushIndex < next) {
    why = name + " was accepted before";
    return FlushOutcome::kDuplicate;
  }
  if (flush.flushIndex > next) {
    why = name + " arrived before flush " + std::to_string(next);
    return FlushOutcome::kOutOfOrder;
  }
  if (flush.mutations < 0 || flush.rejected.nan < 0 || flush.rejected.infinite < 0 ||
      flush.rejected.negative < 0 || flush.rays < 0) {
    why = name + " reports a negative count";
    return FlushOutcome::kBadValues;
  }
  if (flush.tallies.size() > kMaxTallyKinds) {
    why = name + " tallies " + std::to_string(flush.tallies.size()) +
          " kinds of proposal (at most " + std::to_string(kMaxTallyKinds) + ")";
    return FlushOutcome::kBadValues;
  }
  for (const MutationTally& t : flush.tallies) {
    if (t.name.empty() || t.name.size() > kMaxTallyName || t.proposed < 0 || t.accepted < 0 ||
        t.accepted > t.proposed) {
      why = name + " has a malformed tally (a name of 1 to " + std::to_string(kMaxTallyName) +
            " characters, 0 <= accepted <= proposed)";
      return FlushOutcome::kBadValues;
    }
  }
  return FlushOutcome::kAccepted;
}

FlushOutcome SplatAggregator::checkFilm(const ChainFlush& flush, const std::string& name,
                                        std::string* problem) const {
  std::string ignored;
  std::string& why = problem ? *problem : ignored;
  if (flush.width != width_ || flush.height != height_ || flush.splats.size() != sums_.size()) {
    why = name + " is " + std::to_string(flush.width) + "x" + std::to_string(flush.height) +
          " with " + std::to_string(flush.splats.size()) + " values; the film is " +
          std::to_string(width_) + "x" + std::to_string(height_) + " (" +
          std::to_string(sums_.size()) + " values)";
    return FlushOutcome::kWrongSize;
  }
  size_t nonFinite = 0;
  for (float v : flush.splats) nonFinite += !std::isfinite(v);
  if (nonFinite > 0) {
    why = name + " holds " + std::to_string(nonFinite) + " NaN or infinite splat values";
    return FlushOutcome::kBadValues;
  }
  return FlushOutcome::kAccepted;
}

}  // namespace farm
