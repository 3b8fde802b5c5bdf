#pragma once
// Primary sample space for Kelemen-style MLT (Kelemen et al. 2002): the path is a function of an
// infinite vector of uniform numbers, and the Markov chain walks on that vector. Large steps draw
// a fresh vector; small steps perturb each coordinate. Coordinates are mutated lazily, when a
// path first reads them in an iteration, so a chain pays only for the numbers its paths use.
//
// Which coordinates a path reads depends on the sample (path lengths, Russian roulette, mmlt's
// choice of length and strategy). A coordinate the current path does not read is redrawn
// uniformly when a proposal reads it: the target does not depend on it, so that is a Gibbs step
// that keeps the target, and the move after it keeps it uniform. The previous scheme caught it
// up with the small steps it had skipped, redrawn after each rejection: given the rejection they
// were not such steps, and mmlt's chains drifted towards long paths (2-3% too dark on the
// Cornell box's light, its blue channel 2.4% low; PssmltExactness.LazyCoordinatesOfVaryingLengths).
#include <cstdint>
#include <string>
#include <vector>

#include "common/math/vec.h"
#include "common/sampling/rng.h"
#include "common/sampling/sampler.h"

namespace farm {

class PrimarySampleSampler final : public Sampler {
 public:
  PrimarySampleSampler(uint64_t seed, uint64_t stream, float largeStepProbability);

  // Starts the chain at a seed vector (the layout of RecordingSampler::values()).
  void setSeed(const std::vector<float>& values);
  // Begins a proposal: decides between a large and a small step.
  void startIteration();
  // Rewinds the stream positions before a path is (re)built from the vector.
  void startPath() { streamIndex_[0] = streamIndex_[1] = 0; }
  void accept();
  void reject();  // restores every coordinate the rejected proposal touched
  bool isLargeStep() const { return largeStep_; }
  // While frozen, next() reads the current vector without mutating it (re-evaluating the
  // current state after a resume).
  void setFrozen(bool frozen) { frozen_ = frozen; }

  float next(SampleStream stream) override;

  // The chain's own random numbers (acceptance tests) come from the same stream.
  Rng& rng() { return rng_; }

  std::string serialize() const;
  bool deserialize(const std::string& bytes);  // false when the bytes are not a state

 private:
  struct Coordinate {
    float value = 0;
    int64_t lastModified = 0;  // iteration of the last proposal that read it
    float backupValue = 0;
    int64_t backupModified = 0;
    bool readByCurrent = false;  // the current path reads it
  };
  // Moves coordinate `index` for this proposal (once per iteration), backing it up.
  void ensureReady(size_t index);
  // Appends fresh uniform coordinates up to `index`, as read before this iteration.
  void grow(size_t index);

  Rng rng_;
  float largeStepProbability_;
  std::vector<Coordinate> x_;
  std::vector<uint32_t> touched_;       // coordinates the proposal read (and moved)
  std::vector<uint32_t> currentReads_;  // coordinates the current path reads
  int64_t iteration_ = 0;
  bool largeStep_ = true;
  bool frozen_ = false;
  uint32_t streamIndex_[kStreamCount] = {0, 0};
};

// An independent sampler that remembers what it handed out, in the primary-sample layout
// (coordinate k of stream s at index k * kStreamCount + s): how a bootstrap candidate becomes
// a chain's seed vector.
class RecordingSampler final : public Sampler {
 public:
  explicit RecordingSampler(Rng* rng) : rng_(rng) {}
  float next(SampleStream stream) override;
  // The vector; coordinates a stream did not reach are filled with fresh uniform numbers.
  std::vector<float> values();

 private:
  Rng* rng_;
  std::vector<float> values_;
  std::vector<char> used_;
  uint32_t streamIndex_[kStreamCount] = {0, 0};
};

// Small-step kernel: a Gaussian of this standard deviation, wrapped onto [0, 1).
constexpr float kSmallStepSigma = 0.01f;

}  // namespace farm
