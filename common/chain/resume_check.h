#pragma once
// The resume contract every chain kind keeps, as a check for its tests (test code only): run
// whole, and resumed from the state its flush `from` reported, a chain produces the same later
// flushes bit for bit.
#include <gtest/gtest.h>

#include <functional>
#include <vector>

#include "common/chain/chain_spec.h"

namespace farm {

using FlushSink = std::function<bool(ChainFlush&&)>;

// run(spec, sink) runs one chain. Returns the uninterrupted run's flushes.
template <typename Run>
std::vector<ChainFlush> expectResumesExactly(const ChainSpec& spec, size_t from, Run run) {
  std::vector<ChainFlush> whole, rest;
  run(spec, FlushSink([&](ChainFlush&& f) {
        whole.push_back(std::move(f));
        return true;
      }));
  EXPECT_GT(whole.size(), from + 1) << "too few flushes to resume between";
  if (whole.size() <= from + 1) return whole;
  ChainSpec resumed = spec;
  resumed.resumeState = whole[from].state;
  resumed.resumeFlushIndex = uint32_t(from + 1);
  resumed.resumeMutations = 0;
  for (size_t i = 0; i <= from; ++i) resumed.resumeMutations += whole[i].mutations;
  run(resumed, FlushSink([&](ChainFlush&& f) {
        rest.push_back(std::move(f));
        return true;
      }));
  EXPECT_EQ(rest.size(), whole.size() - from - 1);
  for (size_t k = 0; k < rest.size() && from + 1 + k < whole.size(); ++k) {
    const ChainFlush& expected = whole[from + 1 + k];
    EXPECT_EQ(rest[k].flushIndex, expected.flushIndex);
    EXPECT_EQ(rest[k].mutations, expected.mutations);
    EXPECT_EQ(rest[k].splats, expected.splats) << "flush " << expected.flushIndex;
    EXPECT_EQ(rest[k].state, expected.state) << "flush " << expected.flushIndex;
    EXPECT_EQ(rest[k].largeSteps.count, expected.largeSteps.count);
    EXPECT_EQ(rest[k].largeSteps.sum, expected.largeSteps.sum);
  }
  return whole;
}

}  // namespace farm
