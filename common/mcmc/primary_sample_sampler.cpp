#include "common/mcmc/primary_sample_sampler.h"

#include <algorithm>
#include <cmath>

#include "common/math/bytes.h"

namespace farm {

namespace {

// Standard normal deviate from two uniforms (Box-Muller).
float gaussian(Rng& rng) {
  float u1 = 1.0f - rng.nextFloat();  // (0, 1]
  float u2 = rng.nextFloat();
  return std::sqrt(-2.0f * std::log(u1)) * std::cos(2 * kPi * u2);
}

float wrapUnit(float v) {
  v -= std::floor(v);
  return v < 1.0f ? v : 0.0f;  // floor can leave exactly 1 after rounding
}

// "PSS2": each coordinate carries whether the current path reads it. A "PSS1" state (before
// that) still resumes: the chain's rebuild of its current path marks what that path reads, and
// its last large step, which nothing needs now, is skipped.
constexpr uint32_t kStateMagic = 0x50535332;
constexpr uint32_t kStateMagicWithoutReads = 0x50535331;

}  // namespace

PrimarySampleSampler::PrimarySampleSampler(uint64_t seed, uint64_t stream,
                                           float largeStepProbability)
    : rng_(seed, stream), largeStepProbability_(largeStepProbability) {}

void PrimarySampleSampler::setSeed(const std::vector<float>& values) {
  x_.assign(values.size(), Coordinate());
  currentReads_.clear();
  for (size_t i = 0; i < values.size(); ++i) {
    x_[i].value = wrapUnit(values[i]);
    x_[i].lastModified = 0;
  }
  iteration_ = 0;
  touched_.clear();
}

void PrimarySampleSampler::startIteration() {
  ++iteration_;
  touched_.clear();
  largeStep_ = rng_.nextFloat() < largeStepProbability_;
  startPath();
}

void PrimarySampleSampler::grow(size_t index) {
  const size_t old = x_.size();
  x_.resize(index + 1);
  for (size_t i = old; i <= index; ++i) {
    x_[i].value = rng_.nextFloat();
    x_[i].lastModified = iteration_ - 1;
  }
}

void PrimarySampleSampler::ensureReady(size_t index) {
  if (index >= x_.size()) grow(index);
  Coordinate& c = x_[index];
  if (c.lastModified == iteration_) return;  // read already by this proposal
  c.backupValue = c.value;
  c.backupModified = c.lastModified;
  touched_.push_back(uint32_t(index));
  // A coordinate the current path does not read is uniform under the target given the rest
  // (I(u) does not depend on it), so it is redrawn from that, a Gibbs step that leaves the
  // target invariant, before the symmetric move, which then leaves it uniform: it needs no
  // history. Only the coordinates the current path reads take a small step.
  if (largeStep_ || !c.readByCurrent) {
    c.value = rng_.nextFloat();
  } else {
    c.value = wrapUnit(c.value + kSmallStepSigma * gaussian(rng_));
  }
  c.lastModified = iteration_;
}

float PrimarySampleSampler::next(SampleStream stream) {
  const size_t index = size_t(streamIndex_[stream]++) * kStreamCount + size_t(stream);
  if (frozen_) {
    // Rebuilding the current path: what it reads is what the current path reads.
    if (index >= x_.size()) grow(index);
    if (!x_[index].readByCurrent) {
      x_[index].readByCurrent = true;
      currentReads_.push_back(uint32_t(index));
    }
    return x_[index].value;
  }
  ensureReady(index);
  return x_[index].value;
}

void PrimarySampleSampler::accept() {
  // The proposal's coordinates are the current path's now: each was touched once.
  for (uint32_t i : currentReads_) x_[i].readByCurrent = false;
  for (uint32_t i : touched_) x_[i].readByCurrent = true;
  currentReads_.swap(touched_);
  touched_.clear();
}

void PrimarySampleSampler::reject() {
  for (uint32_t i : touched_) {
    x_[i].value = x_[i].backupValue;
    x_[i].lastModified = x_[i].backupModified;
  }
  touched_.clear();
  --iteration_;
}

std::string PrimarySampleSampler::serialize() const {
  std::string s;
  appendBytes(s, kStateMagic);
  appendBytes(s, rng_.state());
  appendBytes(s, rng_.increment());
  appendBytes(s, iteration_);
  appendBytes(s, uint64_t(x_.size()));
  for (const Coordinate& c : x_) {
    appendBytes(s, c.value);
    appendBytes(s, c.lastModified);
    appendBytes(s, uint8_t(c.readByCurrent));
  }
  return s;
}

bool PrimarySampleSampler::deserialize(const std::string& bytes) {
  size_t at = 0;
  uint32_t magic;
  uint64_t state, inc, n;
  int64_t iteration, lastLarge;  // PSS1 only
  if (!readBytes(bytes, at, &magic)) return false;
  if (magic != kStateMagic && magic != kStateMagicWithoutReads) return false;
  const bool withReads = magic == kStateMagic;
  if (!readBytes(bytes, at, &state) || !readBytes(bytes, at, &inc) ||
      !readBytes(bytes, at, &iteration) || (!withReads && !readBytes(bytes, at, &lastLarge)) ||
      !readBytes(bytes, at, &n)) {
    return false;
  }
  const size_t perCoordinate = sizeof(float) + sizeof(int64_t) + (withReads ? 1 : 0);
  if (n > (bytes.size() - at) / perCoordinate) return false;
  std::vector<Coordinate> x(n);
  std::vector<uint32_t> reads;
  for (size_t i = 0; i < x.size(); ++i) {
    Coordinate& c = x[i];
    if (!readBytes(bytes, at, &c.value) || !readBytes(bytes, at, &c.lastModified)) return false;
    if (!(c.value >= 0 && c.value < 1) || c.lastModified > iteration) return false;
    uint8_t read = 0;
    if (withReads && (!readBytes(bytes, at, &read) || read > 1)) return false;
    c.readByCurrent = read != 0;
    if (read) reads.push_back(uint32_t(i));
  }
  rng_.restore(state, inc);
  iteration_ = iteration;
  x_ = std::move(x);
  currentReads_ = std::move(reads);
  touched_.clear();
  return true;
}

float RecordingSampler::next(SampleStream stream) {
  size_t index = size_t(streamIndex_[stream]++) * kStreamCount + size_t(stream);
  if (index >= values_.size()) {
    values_.resize(index + 1, 0.0f);
    used_.resize(index + 1, 0);
  }
  float v = rng_->nextFloat();
  values_[index] = v;
  used_[index] = 1;
  return v;
}

std::vector<float> RecordingSampler::values() {
  for (size_t i = 0; i < values_.size(); ++i) {
    if (!used_[i]) values_[i] = rng_->nextFloat();
  }
  return values_;
}

}  // namespace farm
