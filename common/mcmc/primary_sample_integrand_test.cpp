// Multiplexed MLT divides a strategy's contribution by the probability of having chosen its
// path length, so that probability must be the share of the unit interval that maps to the
// length, exactly: a length whose reported probability is off by a factor is off by that
// factor in the image.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "common/mcmc/primary_sample_integrand.h"

namespace farm {
namespace {

TEST(MultiplexedDepth, ProbabilityIsTheShareOfTheUnitIntervalItOwns) {
  constexpr int kPoints = 1 << 20;
  for (int maxDepth : {1, 3, 7, 65, -1}) {
    std::map<int, int64_t> counts;
    std::map<int, double> probabilities;
    for (int i = 0; i < kPoints; ++i) {
      const float u = (float(i) + 0.5f) / float(kPoints);
      double p;
      const int depth = chooseMultiplexedDepth(u, maxDepth, &p);
      ASSERT_GE(depth, 1);
      if (maxDepth > 0) {
        ASSERT_LE(depth, maxDepth);
      }
      ++counts[depth];
      // Every number that maps to a length reports the same probability.
      if (probabilities.count(depth)) {
        ASSERT_EQ(probabilities[depth], p) << "depth " << depth;
      }
      probabilities[depth] = p;
    }
    double total = 0;
    for (const auto& [depth, p] : probabilities) {
      total += p;
      // The grid's share of a length is exact up to the two grid cells at its ends.
      EXPECT_NEAR(double(counts[depth]) / kPoints, p, 2.0 / kPoints)
          << "max depth " << maxDepth << ", depth " << depth;
    }
    // Where the grid reaches every length the probabilities sum to one; otherwise the lengths
    // it does not reach (beyond about 48) hold what is missing, a few grid cells: the tail
    // beyond the length of the last cell, and the lengths shorter than a cell before it.
    const bool everyLength = maxDepth > 0 && int(counts.size()) == maxDepth;
    EXPECT_NEAR(total, 1.0, everyLength ? 1e-12 : 4.0 / kPoints) << "max depth " << maxDepth;
  }
}

}  // namespace
}  // namespace farm
