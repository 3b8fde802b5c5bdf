#pragma once
// Sums the chains' splat flushes in double precision, accepting each (chain, flush index)
// exactly once and in order: a retried upload or a flush from a worker whose lease moved on is a
// duplicate and changes nothing (docs/design.md, "The work unit"). The image is that sum. With
// two or more error groups of chains (ChainSpec::errorGroup) each group is also summed apart, so
// that the spread between the groups' images estimates the image's error
// (common/film/batch_means.h). Those films are float: the estimate needs the groups' spread, not
// their last digits, and a float sum of n flushes (of splats >= 0) is within a relative n * 2^-24
// of its value. A 4-group 3840x2160 job keeps 190 MiB for the image and 4 x 95 MiB for the
// groups, where it kept 4 x 190 MiB (docs/scale.md, "Memory at 4K").
#include <cstdint>
#include <string>
#include <vector>

#include "common/render/algorithm_pilot.h"
#include "common/render/render_job.h"

namespace farm {

enum class FlushOutcome {
  kAccepted,
  kDuplicate,     // this (chain, flush index) was accepted before
  kOutOfOrder,    // a later flush index than the next one expected: an earlier one is missing
  kUnknownChain,  // chain index out of range
  kWrongSize,     // width, height or splat count differ from the film
  kBadValues,     // negative mutations, or a splat that is NaN or infinite
};

// A worker's upload of several chains' flushes of one job in one (issue 8, part 4): `film`
// carries the entries' splats summed (and the film's size; its other fields are unused), each
// entry one chain's counts, state and flush index (its splats empty), under the lease epoch
// beside it. The aggregator takes a batch whole or not at all: the film cannot be split, and so
// its chains must be of one error group.
struct FlushBatch {
  ChainFlush film;
  std::vector<ChainFlush> entries;
  std::vector<uint64_t> epochs;  // one per entry

  // A single flush as a batch of one: its splats become the film, the rest its entry.
  static FlushBatch of(ChainFlush flush, uint64_t epoch);
};

// What a worker may name in its flushes' tallies: mlt names 13 kinds (its mutations, the manifold
// walks and their causes of loss, manifold_walk.h), the longest 31 characters.
constexpr size_t kMaxTallyKinds = 24;
constexpr size_t kMaxTallyName = 32;

class SplatAggregator {
 public:
  // Everything the aggregator has summed: what a durable coordinator checkpoints
  // (coordinator/job_store.h) and restores from.
  struct Snapshot {
    std::vector<double> sums;                   // the image's film (width*height*3)
    std::vector<std::vector<float>> groupSums;  // each group's film (none with one group)
    std::vector<int64_t> groupWork;             // per group (empty: one group, workDone)
    std::vector<uint32_t> nextFlush;            // per chain
    int64_t workDone = 0;
    int64_t priorWork = 0;  // of workDone, the prior's (addPrior)
    InvalidSplats rejected;
    int64_t rays = 0;
    uint64_t acceptedFlushes = 0;
    std::vector<MutationTally> tallies;
    LargeStepSums largeSteps;
  };

  // chainGroups: each chain's error group (0 .. groups - 1).
  SplatAggregator(int width, int height, std::vector<uint32_t> chainGroups);
  // numChains chains in one group.
  SplatAggregator(int width, int height, uint32_t numChains);
  // Continues from a snapshot of an aggregator of the same film, chains and groups.
  SplatAggregator(int width, int height, std::vector<uint32_t> chainGroups, Snapshot snapshot);
  // How many groups chainGroups names (1 + the largest; 1 when empty).
  static uint32_t groupCount(const std::vector<uint32_t>& chainGroups);
  // How many films of their own `groups` groups keep: one each with two or more, none with one
  // (its film is the image's).
  static uint32_t groupFilmCount(uint32_t groups) { return groups >= 2 ? groups : 0; }

  // What addBatch() would answer, changing nothing, in parts: a flush's place and counts (what a
  // batch entry carries), its film, and the entries' groups. A durable coordinator records a
  // batch between these and addBatch(), so that one it could not record is not summed either.
  FlushOutcome checkEntry(const ChainFlush& flush, std::string* problem = nullptr) const;
  FlushOutcome checkFilm(const ChainFlush& flush, const std::string& name,
                         std::string* problem = nullptr) const;
  // kBadValues when the batch's entries (of chains that exist) are of more than one error group.
  FlushOutcome checkGroups(const FlushBatch& batch, std::string* problem = nullptr) const;
  // A single flush, as a batch of one: adds its splats if it is the next one of its chain;
  // *problem says why not.
  FlushOutcome add(const ChainFlush& flush, std::string* problem = nullptr);
  // Adds the batch's film once and every entry's counts, if every entry is the next flush of
  // its chain (one entry a chain) and the film is sound; otherwise changes nothing and answers
  // the first entry's (or the film's) outcome that is not kAccepted.
  FlushOutcome addBatch(const FlushBatch& batch, std::string* problem = nullptr);
  // Samples taken before the chains that estimate the same image, an allocation pilot's
  // (common/render/algorithm_pilot.h): its film joins the image's, its group g the aggregator's
  // group g mod groups() (the groups stay independent of each other, the pilot's streams being
  // its own), and its counts the work, so that the image is the pooled estimate. Only before
  // any flush (and once): std::logic_error otherwise; std::invalid_argument for a film of
  // another size or counts that do not add up.
  void addPrior(const PilotSamples& prior);
  // withSums false: the counts alone (what an ended job keeps), without copying the film.
  Snapshot snapshot(bool withSums = true) const;

  // The summed splats (width*height*3), for RenderJob::resolve.
  const std::vector<double>& sums() const { return sums_; }
  uint32_t groups() const { return uint32_t(groupWork_.size()); }
  // Group `group`'s film, with two or more groups (with one, sums() is its film).
  const std::vector<float>& groupSums(uint32_t group) const { return groupSums_.at(group); }
  int64_t groupWork(uint32_t group) const { return groupWork_.at(group); }
  int64_t workDone() const { return workDone_; }
  // Of workDone(), the prior's: the chains' own work is the difference.
  int64_t priorWork() const { return priorWork_; }
  const InvalidSplats& rejected() const { return rejected_; }
  int64_t rays() const { return rays_; }
  uint64_t acceptedFlushes() const { return acceptedFlushes_; }
  // Proposals and acceptances of the accepted flushes, by kind, in order of first appearance.
  const std::vector<MutationTally>& tallies() const { return tallies_; }
  // The accepted flushes' large steps, which refine Z (RenderJob::imageScale).
  const LargeStepSums& largeSteps() const { return largeSteps_; }
  // The flush index the chain's next accepted flush must carry.
  uint32_t nextFlushIndex(uint32_t chain) const { return nextFlush_.at(chain); }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  void countFlush(const ChainFlush& flush);  // a checked flush's counts; its chain moves on

  size_t filmValues() const { return size_t(width_) * size_t(height_) * 3; }

  int width_, height_;
  std::vector<uint32_t> chainGroup_;
  std::vector<double> sums_;
  std::vector<std::vector<float>> groupSums_;  // empty with one group
  std::vector<int64_t> groupWork_;
  std::vector<uint32_t> nextFlush_;
  int64_t workDone_ = 0;
  int64_t priorWork_ = 0;
  InvalidSplats rejected_;
  int64_t rays_ = 0;
  uint64_t acceptedFlushes_ = 0;
  std::vector<MutationTally> tallies_;
  LargeStepSums largeSteps_;
};

}  // namespace farm
