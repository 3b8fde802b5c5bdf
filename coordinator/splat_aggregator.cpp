#include "coordinator/splat_aggregator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace farm {

uint32_t SplatAggregator::groupCount(const std::vector<uint32_t>& chainGroups) {
  uint32_t groups = 1;
  for (uint32_t g : chainGroups) groups = std::max(groups, g + 1);
  return groups;
}

SplatAggregator::SplatAggregator(int width, int height, std::vector<uint32_t> chainGroups)
    : width_(width),
      height_(height),
      chainGroup_(std::move(chainGroups)),
      sums_(filmValues(), 0.0),
      groupWork_(groupCount(chainGroup_), 0),
      nextFlush_(chainGroup_.size(), 0) {
  // One film at a time: assign() from a prototype would allocate a film for none as well.
  for (uint32_t g = 0; g < groupFilmCount(uint32_t(groupWork_.size())); ++g)
    groupSums_.emplace_back(filmValues());
}

SplatAggregator::SplatAggregator(int width, int height, uint32_t numChains)
    : SplatAggregator(width, height, std::vector<uint32_t>(numChains, 0)) {}

SplatAggregator::SplatAggregator(int width, int height, std::vector<uint32_t> chainGroups,
                                 Snapshot snapshot)
    : width_(width),
      height_(height),
      chainGroup_(std::move(chainGroups)),
      nextFlush_(std::move(snapshot.nextFlush)),
      workDone_(snapshot.workDone),
      priorWork_(snapshot.priorWork),
      rejected_(snapshot.rejected),
      rays_(snapshot.rays),
      acceptedFlushes_(snapshot.acceptedFlushes),
      tallies_(std::move(snapshot.tallies)),
      largeSteps_(snapshot.largeSteps) {
  const size_t groups = groupCount(chainGroup_), values = filmValues();
  const std::string film = std::to_string(width) + "x" + std::to_string(height) + "x3";
  if (snapshot.sums.size() != values) {
    throw std::invalid_argument("the snapshot's film holds " +
                                std::to_string(snapshot.sums.size()) + " values, not " + film);
  }
  const size_t groupFilms = groupFilmCount(uint32_t(groups));
  if (values == 0 && snapshot.groupSums.empty())  // an ended job's counts: no films
    snapshot.groupSums.resize(groupFilms);
  if (snapshot.groupSums.size() != groupFilms) {
    throw std::invalid_argument("the snapshot holds " + std::to_string(snapshot.groupSums.size()) +
                                " group film(s), not " + std::to_string(groupFilms));
  }
  for (const std::vector<float>& g : snapshot.groupSums) {
    if (g.size() != values)
      throw std::invalid_argument("a group's film in the snapshot holds " +
                                  std::to_string(g.size()) + " values, not " + film);
  }
  if (priorWork_ < 0 || priorWork_ > workDone_) {
    throw std::invalid_argument("the snapshot's prior work " + std::to_string(priorWork_) +
                                " is not within its work " + std::to_string(workDone_));
  }
  if (nextFlush_.empty()) nextFlush_.assign(chainGroup_.size(), 0);  // an ended job's counts
  if (nextFlush_.size() != chainGroup_.size()) {
    throw std::invalid_argument("the snapshot has " + std::to_string(nextFlush_.size()) +
                                " chains, not " + std::to_string(chainGroup_.size()));
  }
  if (snapshot.groupWork.empty() && groups == 1) snapshot.groupWork = {workDone_};
  if (snapshot.groupWork.size() != groups) {
    throw std::invalid_argument("the snapshot counts the work of " +
                                std::to_string(snapshot.groupWork.size()) + " group(s), not " +
                                std::to_string(groups));
  }
  groupWork_ = std::move(snapshot.groupWork);
  sums_ = std::move(snapshot.sums);
  groupSums_ = std::move(snapshot.groupSums);
}

SplatAggregator::Snapshot SplatAggregator::snapshot(bool withSums) const {
  Snapshot s;
  if (withSums) {
    s.sums = sums_;
    s.groupSums = groupSums_;
  }
  s.groupWork = groupWork_;
  s.nextFlush = nextFlush_;
  s.workDone = workDone_;
  s.priorWork = priorWork_;
  s.rejected = rejected_;
  s.rays = rays_;
  s.acceptedFlushes = acceptedFlushes_;
  s.tallies = tallies_;
  s.largeSteps = largeSteps_;
  return s;
}

void SplatAggregator::addPrior(const PilotSamples& prior) {
  if (acceptedFlushes_ > 0 || workDone_ > 0)
    throw std::logic_error("a prior joins the sums before any flush, and once");
  const size_t values = filmValues();
  if (prior.sums.size() != values)
    throw std::invalid_argument("the prior's film holds " + std::to_string(prior.sums.size()) +
                                " values, not " + std::to_string(values));
  if (prior.groupSums.size() != prior.groupWork.size() || prior.groupWork.empty())
    throw std::invalid_argument("the prior's groups and their work do not match");
  int64_t work = 0;
  for (size_t g = 0; g < prior.groupWork.size(); ++g) {
    if (prior.groupSums[g].size() != values || prior.groupWork[g] < 0)
      throw std::invalid_argument("the prior's group " + std::to_string(g) + " is not sound");
    work += prior.groupWork[g];
  }
  if (work != prior.work || work <= 0)
    throw std::invalid_argument("the prior's work " + std::to_string(prior.work) +
                                " is not its groups' " + std::to_string(work));
  for (size_t k = 0; k < values; ++k) sums_[k] += prior.sums[k];
  const uint32_t groups = this->groups();
  for (size_t g = 0; g < prior.groupWork.size(); ++g) {
    const uint32_t into = uint32_t(g % groups);
    groupWork_[into] += prior.groupWork[g];
    if (groupSums_.empty()) continue;  // one group: its film is the image's
    std::vector<float>& film = groupSums_[into];
    for (size_t k = 0; k < values; ++k) film[k] += prior.groupSums[g][k];
  }
  workDone_ += work;
  priorWork_ = work;
}

FlushBatch FlushBatch::of(ChainFlush flush, uint64_t epoch) {
  FlushBatch batch;
  batch.film.width = flush.width;
  batch.film.height = flush.height;
  batch.film.splats = std::move(flush.splats);
  flush.splats.clear();
  batch.entries.push_back(std::move(flush));
  batch.epochs.push_back(epoch);
  return batch;
}

FlushOutcome SplatAggregator::add(const ChainFlush& flush, std::string* problem) {
  return addBatch(FlushBatch::of(flush, 0), problem);
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
  const FlushOutcome groups = checkGroups(batch, problem);
  if (groups != FlushOutcome::kAccepted) return groups;
  const uint32_t group = chainGroup_[batch.entries.front().chainIndex];
  const FlushOutcome film = checkFilm(batch.film, "the batch's film", problem);
  if (film != FlushOutcome::kAccepted) return film;
  const std::vector<float>& splats = batch.film.splats;
  for (size_t i = 0; i < sums_.size(); ++i) sums_[i] += double(splats[i]);
  if (!groupSums_.empty()) {
    std::vector<float>& groupSums = groupSums_[group];
    for (size_t i = 0; i < groupSums.size(); ++i) groupSums[i] += splats[i];
  }
  for (const ChainFlush& entry : batch.entries) countFlush(entry);
  return FlushOutcome::kAccepted;
}

FlushOutcome SplatAggregator::checkGroups(const FlushBatch& batch, std::string* problem) const {
  const ChainFlush* first = nullptr;
  for (const ChainFlush& entry : batch.entries) {
    if (entry.chainIndex >= chainGroup_.size()) continue;  // checkEntry's to answer
    if (!first) first = &entry;
    const uint32_t a = chainGroup_[first->chainIndex], b = chainGroup_[entry.chainIndex];
    if (a != b) {
      if (problem)
        *problem = "the batch sums chains of error groups " + std::to_string(a) + " and " +
                   std::to_string(b) + " (chains " + std::to_string(first->chainIndex) + " and " +
                   std::to_string(entry.chainIndex) + ") into one film";
      return FlushOutcome::kBadValues;
    }
  }
  return FlushOutcome::kAccepted;
}

void SplatAggregator::countFlush(const ChainFlush& flush) {
  workDone_ += flush.mutations;
  groupWork_[chainGroup_[flush.chainIndex]] += flush.mutations;
  rejected_ += flush.rejected;
  rays_ += flush.rays;
  largeSteps_ += flush.largeSteps;
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

FlushOutcome SplatAggregator::checkEntry(const ChainFlush& flush, std::string* problem) const {
  std::string ignored;
  std::string& why = problem ? *problem : ignored;
  const std::string name =
      "flush " + std::to_string(flush.flushIndex) + " of chain " + std::to_string(flush.chainIndex);
  if (flush.chainIndex >= nextFlush_.size()) {
    why = "the job has no chain " + std::to_string(flush.chainIndex) + " (it has " +
          std::to_string(nextFlush_.size()) + ")";
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
  if (!flush.largeSteps.plausible() || flush.largeSteps.count > flush.mutations) {
    why = name + " reports large steps that no chain makes (negative or non-finite sums, or " +
          "more large steps than mutations)";
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
  if (flush.width != width_ || flush.height != height_ || flush.splats.size() != filmValues()) {
    why = name + " is " + std::to_string(flush.width) + "x" + std::to_string(flush.height) +
          " with " + std::to_string(flush.splats.size()) + " values; the film is " +
          std::to_string(width_) + "x" + std::to_string(height_) + " (" +
          std::to_string(filmValues()) + " values)";
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
