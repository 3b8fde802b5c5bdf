// The batch-means error estimate against the error it estimates: groups drawn around a known
// image with known variances, so that the expected relative MSE of their mean is known exactly.
#include "common/film/batch_means.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace farm {
namespace {

struct Drawn {
  std::vector<Image> groups;
  std::vector<double> work;
  Image mean;
  double expectedRelMse = 0;  // E[(mean - truth)^2 / (truth^2 + 0.01)], averaged
};

// G groups of unequal work around a random image: group g's values have variance
// sigma^2 truth^2 / W_g (a relative noise), so their work-weighted mean has sigma^2 truth^2 / W.
Drawn draw(const std::vector<double>& work, double sigma, uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> value(0.05, 4.0);
  std::normal_distribution<double> normal;
  const int w = 200, h = 100;
  Image truth(w, h);
  for (float& v : truth.rgb) v = float(value(rng));
  Drawn d;
  d.work = work;
  double total = 0;
  for (double wg : work) total += wg;
  d.mean = Image(w, h);
  for (double wg : work) {
    Image g(w, h);
    for (size_t i = 0; i < g.rgb.size(); ++i) {
      g.rgb[i] = float(truth.rgb[i] * (1 + sigma / std::sqrt(wg) * normal(rng)));
      d.mean.rgb[i] += float(wg / total * g.rgb[i]);
    }
    d.groups.push_back(std::move(g));
  }
  for (float r : truth.rgb) {
    d.expectedRelMse += sigma * sigma * r * r / total / (double(r) * r + 1e-2);
  }
  d.expectedRelMse /= double(truth.rgb.size());
  return d;
}

TEST(BatchMeans, EstimatesTheRelativeMseOfGroupsOfUnequalWork) {
  // 60000 channel values, three degrees of freedom each: the estimate's own relative error is
  // about sqrt(2 / 3 / 60000) = 0.3%. The groups' median in place of the truth in the
  // denominator biases it by E[1 / (1 + e)^2] - 1 = 3 Var(e) for a relative error e of the
  // median: about 1% at the equal groups' (the median of four of relative variance 0.1^2 has
  // about 0.3 of it).
  for (const std::vector<double>& work :
       {std::vector<double>{1, 1, 1, 1}, std::vector<double>{1, 2, 3, 10}}) {
    Drawn d = draw(work, 0.1, 7);
    ErrorEstimate e;
    std::string error;
    ASSERT_TRUE(estimateError(d.groups, d.work, d.mean, 0, &e, &error)) << error;
    EXPECT_NEAR(e.relMse, d.expectedRelMse, 0.02 * d.expectedRelMse) << work[3];
    EXPECT_GT(e.rmse, 0);
  }
}

TEST(BatchMeans, AFireflyOfOneGroupWeighsAsItDoesAgainstTheReference) {
  // 100 values of 1 in every group, but one group found 1000 at the first: the mean there is
  // 250.75, whose squared error against the truth (1) is 61757 relative. Weighed by the
  // image's own square, it would count about 1.
  std::vector<Image> groups(4, Image(10, 10));
  for (Image& g : groups)
    for (float& v : g.rgb) v = 1;
  groups[0].rgb[0] = 1000;
  Image mean(10, 10);
  for (size_t i = 0; i < mean.rgb.size(); ++i)
    mean.rgb[i] =
        0.25f * (groups[0].rgb[i] + groups[1].rgb[i] + groups[2].rgb[i] + groups[3].rgb[i]);
  ErrorEstimate e;
  ASSERT_TRUE(estimateError(groups, {1, 1, 1, 1}, mean, 0, &e, nullptr));
  const double reference = 249.75 * 249.75 / 1.01 / 300;
  EXPECT_NEAR(e.relMse, reference, 0.02 * reference);
}

TEST(BatchMeans, AddsTheSharedNormalizationsVariance) {
  // Groups that agree exactly: only Z's error is left, x^2 Var(Z)/Z^2 / (x^2 + 0.01) a value.
  Image image(2, 1);
  image.rgb = {1, 2, 0.1f, 0, 3, 1};
  std::vector<Image> groups(3, image);
  ErrorEstimate e;
  ASSERT_TRUE(estimateError(groups, {1, 2, 3}, image, 0.01, &e, nullptr));
  double expected = 0;
  for (float x : image.rgb) expected += 0.01 * x * x / (double(x) * x + 1e-2);
  EXPECT_NEAR(e.relMse, expected / 6, 1e-9);
  ASSERT_TRUE(estimateError(groups, {1, 2, 3}, image, 0, &e, nullptr));
  EXPECT_EQ(e.relMse, 0);
}

TEST(BatchMeans, RefusesWhatItCannotEstimate) {
  Image image(2, 2), other(3, 2);
  ErrorEstimate e;
  std::string error;
  EXPECT_FALSE(estimateError({image}, {1}, image, 0, &e, &error));
  EXPECT_NE(error.find("at least two groups"), std::string::npos) << error;
  EXPECT_FALSE(estimateError({image, other}, {1, 1}, image, 0, &e, &error));
  EXPECT_FALSE(estimateError({image, image}, {1, 0}, image, 0, &e, &error));
  EXPECT_FALSE(estimateError({image, image}, {1}, image, 0, &e, &error));
}

}  // namespace
}  // namespace farm
