#pragma once
// PCG32 (O'Neill 2014): small state, independent streams. Every chain and every sample derives
// its stream from (job seed, index) so a work unit produces the same numbers on any host.
#include <cstdint>

namespace farm {

class Rng {
 public:
  Rng() { seed(0, 0); }
  Rng(uint64_t seedValue, uint64_t stream) { seed(seedValue, stream); }

  void seed(uint64_t seedValue, uint64_t stream) {
    state_ = 0u;
    inc_ = (stream << 1u) | 1u;
    nextUint();
    state_ += seedValue;
    nextUint();
  }

  uint32_t nextUint() {
    uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
  }

  // Uniform in [0, 1): 24 random mantissa bits, never rounds up to 1.
  float nextFloat() { return float(nextUint() >> 8) * 0x1p-24f; }
  double nextDouble() {
    uint64_t hi = nextUint(), lo = nextUint();
    return double(((hi << 32) | lo) >> 11) * 0x1p-53;
  }

  uint64_t state() const { return state_; }
  uint64_t increment() const { return inc_; }
  void restore(uint64_t state, uint64_t inc) {
    state_ = state;
    inc_ = inc;
  }

 private:
  uint64_t state_ = 0, inc_ = 1;
};

// A well-mixed 64-bit hash (splitmix64 finalizer) to derive stream ids from several indices.
inline uint64_t mixBits(uint64_t v) {
  v ^= v >> 31;
  v *= 0x7fb5d329728ea185ULL;
  v ^= v >> 27;
  v *= 0x81dadef4bc2dd44dULL;
  v ^= v >> 33;
  return v;
}
inline uint64_t streamId(uint64_t a, uint64_t b) {
  return mixBits(mixBits(a) ^ (b * 0x9e3779b97f4a7c15ULL));
}

}  // namespace farm
