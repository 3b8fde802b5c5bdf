// The batch-means error estimate against the error it estimates: groups drawn around a known
// image with known variances, so that the expected relative MSE of their mean is known exactly.
#include "common/film/batch_means.h"

#include <gtest/gtest.h>

#include <algorithm>
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

// G groups of unequal work around a smooth image (0.5 .. 3.5, waves of about 100 pixels, as a
// render's shading varies; the estimate takes r^2 from a pixel's neighbours): group g's values
// have variance sigma^2 truth^2 / W_g (a relative noise), so their work-weighted mean has
// sigma^2 truth^2 / W.
Drawn draw(const std::vector<double>& work, double sigma, uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const int w = 200, h = 100;
  Image truth(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        truth.rgb[(size_t(y) * w + x) * 3 + c] =
            float(2.0 + 1.5 * std::sin(x / 20.0 + c) * std::cos(y / 15.0 + 2 * c));
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
  // about sqrt(2 / 3 / 60000) = 0.3%. The neighbours' r^2 in place of the pixel's biases it by
  // how r^2 bends within the window: -1.7% on this image (the truth's own r^2 / (r^2 + 0.01)
  // over its neighbours' mean, computed apart); the pairs' noise in that mean adds +0.02%.
  // Hence 3%.
  for (const std::vector<double>& work :
       {std::vector<double>{1, 1, 1, 1}, std::vector<double>{1, 2, 3, 10}}) {
    Drawn d = draw(work, 0.1, 7);
    ErrorEstimate e;
    std::string error;
    ASSERT_TRUE(estimateError(d.groups, d.work, d.mean, 0, &e, &error)) << error;
    EXPECT_NEAR(e.relMse, d.expectedRelMse, 0.03 * d.expectedRelMse) << work[3];
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

TEST(BatchMeans, LightInRareBrightSamplesWeighsAsItDoesAgainstTheReference) {
  // Every pixel's light arrives in rare samples: each of n = 4 samples a group is 1 / p with
  // probability p = 0.1, else 0, so r = 1 everywhere and the mean of G = 4 groups has variance
  // (1 / p - 1) / (G n) = 0.5625, relative MSE 0.5625 / 1.01. A pixel's groups mostly see
  // less than r (66% of groups see nothing): their median, or the pixel's own products, put a
  // denominator near 0.01 and the estimate some 40x too high. The neighbours' mean of the
  // pairs' r^2 has relative variance about 3.1 / 80 (the U-statistic's over G = 4 groups of
  // relative variance 2.25, then 80 neighbours), which biases 1 / (r^2 + 0.01) by about
  // +3.9%; the estimate's own relative error over 60000 values is under 1%.
  std::mt19937_64 rng(5);
  std::binomial_distribution<int> hits(4, 0.1);
  const int w = 200, h = 100;
  std::vector<Image> groups(4, Image(w, h));
  Image mean(w, h);
  for (Image& g : groups)
    for (size_t i = 0; i < g.rgb.size(); ++i) {
      g.rgb[i] = float(hits(rng) / 0.4);
      mean.rgb[i] += 0.25f * g.rgb[i];
    }
  ErrorEstimate e;
  ASSERT_TRUE(estimateError(groups, {1, 1, 1, 1}, mean, 0, &e, nullptr));
  const double expected = 0.5625 / 1.01;
  EXPECT_GT(e.relMse, 0.99 * expected);
  EXPECT_LT(e.relMse, 1.08 * expected);
}

TEST(BatchMeans, AddsTheSharedNormalizationsVariance) {
  // Groups that agree exactly: only Z's error is left, x^2 Var(Z)/Z^2 / (r^2 + 0.01) a value,
  // with r^2 its neighbours' (every pixel alike here, so its own).
  Image image(3, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x) image.set(x, y, {1, 2, 0.1f});
  std::vector<Image> groups(3, image);
  ErrorEstimate e;
  ASSERT_TRUE(estimateError(groups, {1, 2, 3}, image, 0.01, &e, nullptr));
  double expected = 0;
  for (double x : {1.0, 2.0, double(0.1f)}) expected += 0.01 * x * x / (x * x + 1e-2);
  EXPECT_NEAR(e.relMse, expected / 3, 1e-6);
  ASSERT_TRUE(estimateError(groups, {1, 2, 3}, image, 0, &e, nullptr));
  EXPECT_EQ(e.relMse, 0);
}

// Images read a band of rows at a time, as the coordinator resolves them from its films: each
// read holds a band and the neighbour window's four rows above and below it, and the estimate
// is the whole images' to rounding, whatever the band (one row, bands that do not divide the
// height, or the whole).
class CountingFilms : public ImageFilms {
 public:
  using ImageFilms::ImageFilms;
  void rows(size_t g, int y0, int y1, float* out) const override {
    mostRows = std::max(mostRows, y1 - y0);
    ImageFilms::rows(g, y0, y1, out);
  }
  mutable int mostRows = 0;
};

TEST(BatchMeans, ReadsTheImagesABandAtATime) {
  const Drawn d = draw({1, 2, 3, 10}, 0.3, 11);
  ErrorEstimate whole;
  ASSERT_TRUE(estimateError(d.groups, d.work, d.mean, 0.001, &whole, nullptr, 100));
  for (int band : {1, 7, 64}) {
    CountingFilms films(d.groups, d.mean);
    ErrorEstimate e;
    ASSERT_TRUE(estimateError(films, d.work, 0.001, &e, nullptr, band));
    EXPECT_NEAR(e.relMse, whole.relMse, 1e-12 * whole.relMse) << band;
    EXPECT_NEAR(e.rmse, whole.rmse, 1e-12 * whole.rmse) << band;
    EXPECT_LE(films.mostRows, band + 8) << band;
  }
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
