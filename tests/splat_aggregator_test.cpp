#include "coordinator/splat_aggregator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace farm {
namespace {

ChainFlush makeFlush(uint32_t chain, uint32_t index, float value, int w = 2, int h = 2) {
  ChainFlush f;
  f.chainIndex = chain;
  f.flushIndex = index;
  f.mutations = 100;
  f.width = w;
  f.height = h;
  f.splats.assign(size_t(w) * h * 3, value);
  return f;
}

TEST(SplatAggregator, AcceptsEachChainFlushExactlyOnce) {
  SplatAggregator sum(2, 2, 3);
  EXPECT_EQ(sum.add(makeFlush(0, 0, 1.0f)), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(makeFlush(0, 0, 1.0f)), FlushOutcome::kDuplicate);
  EXPECT_EQ(sum.add(makeFlush(1, 0, 2.0f)), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(makeFlush(0, 1, 4.0f)), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(makeFlush(0, 1, 4.0f)), FlushOutcome::kDuplicate);
  EXPECT_EQ(sum.add(makeFlush(1, 0, 2.0f)), FlushOutcome::kDuplicate);
  EXPECT_EQ(sum.workDone(), 300);
  EXPECT_EQ(sum.acceptedFlushes(), 3u);
  for (double v : sum.sums()) EXPECT_EQ(v, 7.0);
  EXPECT_EQ(sum.nextFlushIndex(0), 2u);
  EXPECT_EQ(sum.nextFlushIndex(1), 1u);
  EXPECT_EQ(sum.nextFlushIndex(2), 0u);
}

TEST(SplatAggregator, RejectsWhatDoesNotFitWithoutChangingTheSums) {
  SplatAggregator sum(2, 2, 2);
  std::string why;
  EXPECT_EQ(sum.add(makeFlush(2, 0, 1.0f), &why), FlushOutcome::kUnknownChain);
  EXPECT_NE(why.find("does not exist"), std::string::npos);
  EXPECT_EQ(sum.add(makeFlush(0, 1, 1.0f), &why), FlushOutcome::kOutOfOrder);
  EXPECT_EQ(sum.add(makeFlush(0, 0, 1.0f, 3, 2), &why), FlushOutcome::kWrongSize);
  ChainFlush nan = makeFlush(0, 0, 1.0f);
  nan.splats[5] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(sum.add(nan, &why), FlushOutcome::kBadValues);
  ChainFlush inf = makeFlush(0, 0, 1.0f);
  inf.splats[0] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(sum.add(inf, &why), FlushOutcome::kBadValues);
  ChainFlush negative = makeFlush(0, 0, 1.0f);
  negative.mutations = -1;
  EXPECT_EQ(sum.add(negative, &why), FlushOutcome::kBadValues);
  EXPECT_EQ(sum.workDone(), 0);
  for (double v : sum.sums()) EXPECT_EQ(v, 0.0);
  // The rejected flushes did not consume flush index 0.
  EXPECT_EQ(sum.add(makeFlush(0, 0, 1.0f)), FlushOutcome::kAccepted);
}

TEST(SplatAggregator, SumsInDoublePrecision) {
  // 2^24 + 1 is not a float: a float accumulator would lose every one of the small additions.
  SplatAggregator sum(1, 1, 2);
  EXPECT_EQ(sum.add(makeFlush(0, 0, 16777216.0f, 1, 1)), FlushOutcome::kAccepted);
  for (uint32_t i = 0; i < 1000; ++i) {
    ASSERT_EQ(sum.add(makeFlush(1, i, 1.0f, 1, 1)), FlushOutcome::kAccepted);
  }
  EXPECT_EQ(sum.sums()[0], 16777216.0 + 1000.0);
}

}  // namespace
}  // namespace farm
