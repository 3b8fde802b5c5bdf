#include "coordinator/progress_math.h"

#include <gtest/gtest.h>

namespace farm {
namespace {

TEST(ProgressMath, CountBudgetIsAcceptedOverPlanned) {
  ProgressEstimate p = estimateProgress(250, 1000, 0, 12, 10);
  EXPECT_DOUBLE_EQ(p.fraction, 0.25);
  EXPECT_DOUBLE_EQ(p.samplesPerSecond, 25);
  EXPECT_DOUBLE_EQ(p.etaSeconds, 30);  // 750 left at 25/s
}

TEST(ProgressMath, NothingAcceptedYetMeansUnknownEta) {
  ProgressEstimate p = estimateProgress(0, 1000, 0, 5, 0);
  EXPECT_DOUBLE_EQ(p.fraction, 0);
  EXPECT_DOUBLE_EQ(p.samplesPerSecond, 0);
  EXPECT_LT(p.etaSeconds, 0);
}

TEST(ProgressMath, DoneIsOneWithNoEta) {
  ProgressEstimate p = estimateProgress(1000, 1000, 0, 40, 30);
  EXPECT_DOUBLE_EQ(p.fraction, 1);
  EXPECT_DOUBLE_EQ(p.etaSeconds, 0);
  EXPECT_DOUBLE_EQ(estimateProgress(1200, 1000, 0, 40, 30).fraction, 1);
}

TEST(ProgressMath, TimeBudgetIsElapsedOverBudget) {
  ProgressEstimate p = estimateProgress(5000, -1, 20, 5, 4);
  EXPECT_DOUBLE_EQ(p.fraction, 0.25);
  EXPECT_DOUBLE_EQ(p.etaSeconds, 15);
  EXPECT_DOUBLE_EQ(p.samplesPerSecond, 1250);
  EXPECT_DOUBLE_EQ(estimateProgress(5000, -1, 20, 25, 24).fraction, 1);
  EXPECT_DOUBLE_EQ(estimateProgress(5000, -1, 20, 25, 24).etaSeconds, 0);
}

}  // namespace
}  // namespace farm
