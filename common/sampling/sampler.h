#pragma once
// Where the transport algorithms take their random numbers from. An independent sampler for
// Monte Carlo; a primary-sample-space sampler for Kelemen-style MLT, which needs each number to
// keep its meaning across mutations: numbers come from streams (camera subpath, light subpath)
// so that a change in one subpath's length does not shift the other's numbers.
#include "common/sampling/rng.h"

namespace farm {

enum SampleStream : int { kCameraStream = 0, kLightStream = 1, kStreamCount = 2 };

class Sampler {
 public:
  virtual ~Sampler() = default;
  virtual float next(SampleStream stream) = 0;
};

class IndependentSampler final : public Sampler {
 public:
  explicit IndependentSampler(Rng* rng) : rng_(rng) {}
  float next(SampleStream) override { return rng_->nextFloat(); }

 private:
  Rng* rng_;
};

}  // namespace farm
