#pragma once
// The two checks the statistical tests of every Markov chain kernel use. Both need independent
// replicas: many chains, each started from an exact (or resampled) draw of its target.
//
//  - Final states: if every chain starts in the stationary distribution, its state after any
//    number of mutations is again a draw from it, and the chains' final states are independent
//    draws. Their histogram against the target's bin probabilities is a Pearson chi-square test
//    with bins - 1 degrees of freedom.
//  - Splatted shares: what a chain deposits per bin, as a share of all it deposits, has the
//    target's bin probability as its expectation (expected-value splatting included). Averaged
//    over independent chains, each bin's mean has a standard error from the chains' spread; a
//    union bound over the bins (Bonferroni) keeps the test's level whatever their correlation.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "common/math/statistics.h"

namespace farm {

// Pearson's statistic of observed counts against bin probabilities (which sum to one).
inline double pearsonChiSquare(const std::vector<int64_t>& counts, const std::vector<double>& p) {
  int64_t n = 0;
  for (int64_t c : counts) n += c;
  double x2 = 0;
  for (size_t b = 0; b < counts.size(); ++b) {
    double expected = double(n) * p[b];
    double d = double(counts[b]) - expected;
    x2 += expected > 0 ? d * d / expected : (counts[b] > 0 ? INFINITY : 0);
  }
  return x2;
}

struct ShareTest {
  double maxAbsZ = 0;  // largest |mean share - expected| / standard error over the bins
  int worstBin = -1;
  double threshold = 0;  // the Bonferroni bound at the requested level
  bool passed() const { return maxAbsZ <= threshold; }
};

// shares[c][b]: chain c's share of its deposits in bin b. Two-sided, total level alpha.
inline ShareTest testShares(const std::vector<std::vector<double>>& shares,
                            const std::vector<double>& expected, double alpha) {
  ShareTest t;
  const size_t bins = expected.size();
  const double n = double(shares.size());
  t.threshold = normalQuantile(1 - alpha / (2 * double(bins)));
  for (size_t b = 0; b < bins; ++b) {
    double sum = 0, sumSq = 0;
    for (const std::vector<double>& chain : shares) {
      sum += chain[b];
      sumSq += chain[b] * chain[b];
    }
    double mean = sum / n;
    double variance = std::max(0.0, (sumSq - n * mean * mean) / (n - 1));
    double se = std::sqrt(variance / n);
    double z = se > 0 ? std::fabs(mean - expected[b]) / se
                      : (std::fabs(mean - expected[b]) > 1e-12 ? INFINITY : 0);
    if (z > t.maxAbsZ || t.worstBin < 0) {
      t.maxAbsZ = z;
      t.worstBin = int(b);
    }
  }
  return t;
}

}  // namespace farm
