#pragma once
// The flush protocol of docs/design.md in one place: a chain's splats accumulate here between
// flushes, and every spec.flushInterval mutations (and when the budget is spent) they go out as
// a ChainFlush with the count they cover and the chain's state, so that another worker can
// resume exactly there.
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "common/chain/chain_spec.h"
#include "common/film/splat_buffer.h"
#include "common/scene/scene.h"

namespace farm {

class ChainFlusher {
 public:
  ChainFlusher(const ChainSpec& spec, const Scene& scene,
               const std::function<bool(ChainFlush&&)>& onFlush,
               const std::atomic<bool>* cancel = nullptr);

  SplatBuffer& film() { return film_; }
  // Counts a splat that must not reach the image (NaN, infinite or negative) when `value` is
  // one, reported with the next flush; true when the value is valid.
  bool check(const Spectrum& value) { return rejected_.check(value); }
  void reject(const InvalidSplats& counts) { rejected_ += counts; }
  // Mutations (or samples) done so far, resumed ones included.
  int64_t done() const { return done_; }
  // More to do: budget left and not cancelled.
  bool budgetLeft() const {
    if (cancel_ && cancel_->load(std::memory_order_relaxed)) return false;
    return spec_.budget < 0 || done_ < spec_.budget;
  }
  // Counts a proposal of the given kind (a string with static storage) and whether the chain
  // moved; reported with the next flush.
  void tally(const char* kind, bool accepted);
  // `proposed` more of `kind`, `accepted` of them.
  void tally(const char* kind, int64_t proposed, int64_t accepted);
  // Counts a large step whose proposal carried contribution I (accepted or not: its I is an
  // independent sample of the integrand either way); reported with the next flush.
  void largeStep(double I) {
    if (!std::isfinite(I) || I < 0) return;  // an invalid path's I never reaches the chain
    ++largeSteps_.count;
    largeSteps_.sum += I;
    largeSteps_.sumSquares += I * I;
  }
  // Counts one mutation and flushes when one is due; raysTraced is the chain's running total
  // and state() the chain's resumable state. False when the receiver says stop.
  bool countMutation(uint64_t raysTraced, const std::function<std::string()>& state);

 private:
  const ChainSpec& spec_;
  const std::function<bool(ChainFlush&&)>& onFlush_;
  const std::atomic<bool>* cancel_;
  SplatBuffer film_;
  int64_t done_, sinceFlush_ = 0, interval_;
  InvalidSplats rejected_;
  uint32_t flushIndex_;
  uint64_t raysAtFlush_ = 0;
  std::vector<std::pair<const char*, MutationTally>> tallies_;
  LargeStepSums largeSteps_;
};

}  // namespace farm
