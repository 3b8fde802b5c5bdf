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

constexpr uint32_t kStateMagic = 0x50535331;  // "PSS1"

}  // namespace

PrimarySampleSampler::PrimarySampleSampler(uint64_t seed, uint64_t stream,
                                           float largeStepProbability)
    : rng_(seed, stream), largeStepProbability_(largeStepProbability) {}

void PrimarySampleSampler::setSeed(const std::vector<float>& values) {
  x_.assign(values.size(), Coordinate());
  for (size_t i = 0; i < values.size(); ++i) {
    x_[i].value = wrapUnit(values[i]);
    x_[i].lastModified = 0;
  }
  iteration_ = 0;
  lastLargeStep_ = 0;
  touched_.clear();
}

void PrimarySampleSampler::startIteration() {
  ++iteration_;
  touched_.clear();
  largeStep_ = rng_.nextFloat() < largeStepProbability_;
  backupLastLargeStep_ = lastLargeStep_;
  if (largeStep_) lastLargeStep_ = iteration_;
  startPath();
}

void PrimarySampleSampler::ensureReady(size_t index) {
  if (index >= x_.size()) {
    // A coordinate no path has read yet: its value is simply a fresh uniform number.
    size_t old = x_.size();
    x_.resize(index + 1);
    for (size_t i = old; i <= index; ++i) {
      x_[i].value = rng_.nextFloat();
      x_[i].lastModified = iteration_;
      // Restoring after a rejection keeps the value (still a uniform number) and rewinds the
      // time stamp with the iteration counter.
      x_[i].backupValue = x_[i].value;
      x_[i].backupModified = std::max<int64_t>(0, iteration_ - 1);
      if (!frozen_) touched_.push_back(uint32_t(i));
    }
    return;
  }
  Coordinate& c = x_[index];
  if (c.lastModified == iteration_) return;
  c.backupValue = c.value;
  c.backupModified = c.lastModified;
  touched_.push_back(uint32_t(index));
  if (c.lastModified < lastLargeStep_) {
    // A large step since this coordinate was last read: the small steps before it do not matter.
    c.value = rng_.nextFloat();
    c.lastModified = lastLargeStep_;
  }
  int64_t smallSteps = iteration_ - c.lastModified;
  if (smallSteps > 0) {
    // n independent Gaussian steps add up to one of standard deviation sigma sqrt(n).
    float sigma = kSmallStepSigma * std::sqrt(float(smallSteps));
    c.value = wrapUnit(c.value + sigma * gaussian(rng_));
  }
  c.lastModified = iteration_;
}

float PrimarySampleSampler::next(SampleStream stream) {
  size_t index = size_t(streamIndex_[stream]++) * kStreamCount + size_t(stream);
  if (frozen_) {
    if (index >= x_.size()) ensureReady(index);
    return x_[index].value;
  }
  ensureReady(index);
  return x_[index].value;
}

void PrimarySampleSampler::accept() {
  touched_.clear();
}

void PrimarySampleSampler::reject() {
  for (uint32_t i : touched_) {
    x_[i].value = x_[i].backupValue;
    x_[i].lastModified = x_[i].backupModified;
  }
  touched_.clear();
  lastLargeStep_ = backupLastLargeStep_;
  // The chain did not move: coordinates no path read must not accrue this iteration's step.
  --iteration_;
}

std::string PrimarySampleSampler::serialize() const {
  std::string s;
  appendBytes(s, kStateMagic);
  appendBytes(s, rng_.state());
  appendBytes(s, rng_.increment());
  appendBytes(s, iteration_);
  appendBytes(s, lastLargeStep_);
  appendBytes(s, uint64_t(x_.size()));
  for (const Coordinate& c : x_) {
    appendBytes(s, c.value);
    appendBytes(s, c.lastModified);
  }
  return s;
}

bool PrimarySampleSampler::deserialize(const std::string& bytes) {
  size_t at = 0;
  uint32_t magic;
  uint64_t state, inc, n;
  int64_t iteration, lastLarge;
  if (!readBytes(bytes, at, &magic) || magic != kStateMagic) return false;
  if (!readBytes(bytes, at, &state) || !readBytes(bytes, at, &inc) ||
      !readBytes(bytes, at, &iteration) || !readBytes(bytes, at, &lastLarge) ||
      !readBytes(bytes, at, &n)) {
    return false;
  }
  if (n > (bytes.size() - at) / (sizeof(float) + sizeof(int64_t))) return false;
  std::vector<Coordinate> x(n);
  for (Coordinate& c : x) {
    if (!readBytes(bytes, at, &c.value) || !readBytes(bytes, at, &c.lastModified)) return false;
    if (!(c.value >= 0 && c.value < 1) || c.lastModified > iteration) return false;
  }
  rng_.restore(state, inc);
  iteration_ = iteration;
  lastLargeStep_ = lastLarge;
  x_ = std::move(x);
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
