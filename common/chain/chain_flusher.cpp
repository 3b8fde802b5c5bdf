#include "common/chain/chain_flusher.h"

#include <algorithm>

namespace farm {

ChainFlusher::ChainFlusher(const ChainSpec& spec, const Scene& scene,
                           const std::function<bool(ChainFlush&&)>& onFlush,
                           const std::atomic<bool>* cancel)
    : spec_(spec),
      onFlush_(onFlush),
      cancel_(cancel),
      film_(scene.camera().width(), scene.camera().height(),
            PixelFilter::of(scene.description().camera)),
      done_(spec.resumeMutations),
      interval_(std::max<int64_t>(1, spec.flushInterval)),
      flushIndex_(spec.resumeFlushIndex) {}

void ChainFlusher::tally(const char* kind, bool accepted) {
  tally(kind, 1, accepted ? 1 : 0);
}

void ChainFlusher::tally(const char* kind, int64_t proposed, int64_t accepted) {
  for (auto& [name, t] : tallies_) {
    if (name == kind) {
      t.proposed += proposed;
      t.accepted += accepted;
      return;
    }
  }
  tallies_.push_back({kind, MutationTally{kind, proposed, accepted}});
}

bool ChainFlusher::countMutation(uint64_t raysTraced, const std::function<std::string()>& state) {
  ++done_;
  ++sinceFlush_;
  const bool finished = spec_.budget >= 0 && done_ >= spec_.budget;
  if (sinceFlush_ < interval_ && !finished) return true;
  ChainFlush f;
  f.chainIndex = spec_.chainIndex;
  f.flushIndex = flushIndex_++;
  f.mutations = sinceFlush_;
  f.width = film_.width();
  f.height = film_.height();
  // Rounded to float once per flush (the coordinator sums flushes in double).
  f.splats.assign(film_.data().begin(), film_.data().end());
  f.rejected = rejected_;
  f.rays = int64_t(raysTraced - raysAtFlush_);
  f.state = state();
  f.finished = finished;
  for (auto& [name, t] : tallies_) f.tallies.push_back(t);
  tallies_.clear();
  f.largeSteps = largeSteps_;
  largeSteps_ = LargeStepSums();
  raysAtFlush_ = raysTraced;
  film_.clear();
  sinceFlush_ = 0;
  rejected_ = InvalidSplats();
  return onFlush_(std::move(f));
}

}  // namespace farm
