#include "coordinator/splat_aggregator.h"

#include <cmath>

namespace farm {

SplatAggregator::SplatAggregator(int width, int height, uint32_t numChains)
    : width_(width),
      height_(height),
      sums_(size_t(width) * size_t(height) * 3, 0.0),
      nextFlush_(numChains, 0) {}

FlushOutcome SplatAggregator::add(const ChainFlush& flush, std::string* problem) {
  std::string ignored;
  std::string& why = problem ? *problem : ignored;
  const std::string name =
      "flush " + std::to_string(flush.flushIndex) + " of chain " + std::to_string(flush.chainIndex);
  if (flush.chainIndex >= nextFlush_.size()) {
    why = "chain " + std::to_string(flush.chainIndex) + " does not exist (the job has " +
          std::to_string(nextFlush_.size()) + " chains)";
    return FlushOutcome::kUnknownChain;
  }
  uint32_t& next = nextFlush_[flush.chainIndex];
  if (flush.flushIndex < next) {
    why = name + " was accepted before";
    return FlushOutcome::kDuplicate;
  }
  if (flush.flushIndex > next) {
    why = name + " arrived before flush " + std::to_string(next);
    return FlushOutcome::kOutOfOrder;
  }
  if (flush.width != width_ || flush.height != height_ || flush.splats.size() != sums_.size()) {
    why = name + " is " + std::to_string(flush.width) + "x" + std::to_string(flush.height) +
          " with " + std::to_string(flush.splats.size()) + " values; the film is " +
          std::to_string(width_) + "x" + std::to_string(height_) + " (" +
          std::to_string(sums_.size()) + " values)";
    return FlushOutcome::kWrongSize;
  }
  if (flush.mutations < 0 || flush.rejectedSplats < 0 || flush.rays < 0) {
    why = name + " reports a negative count";
    return FlushOutcome::kBadValues;
  }
  // Check everything before adding anything: a rejected flush must leave the sums untouched.
  size_t nonFinite = 0;
  for (float v : flush.splats) nonFinite += !std::isfinite(v);
  if (nonFinite > 0) {
    why = name + " holds " + std::to_string(nonFinite) + " NaN or infinite splat values";
    return FlushOutcome::kBadValues;
  }
  for (size_t i = 0; i < sums_.size(); ++i) sums_[i] += double(flush.splats[i]);
  workDone_ += flush.mutations;
  rejectedSplats_ += flush.rejectedSplats;
  rays_ += flush.rays;
  ++acceptedFlushes_;
  ++next;
  return FlushOutcome::kAccepted;
}

}  // namespace farm
