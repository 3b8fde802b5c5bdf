// The three-cornered hat against errors known exactly: images drawn around a known one with
// known noise, and one that misses light.
#include "common/film/cross_estimate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace farm {
namespace {

constexpr int kWidth = 200, kHeight = 100;

Image truth() {
  Image t(kWidth, kHeight);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      for (int c = 0; c < 3; ++c)
        t.rgb[(size_t(y) * kWidth + x) * 3 + c] =
            float(2.0 + 1.5 * std::sin(x / 20.0 + c) * std::cos(y / 15.0 + 2 * c));
  return t;
}

// The truth with relative Gaussian noise sigma, times `gain` in the image's left half.
Image noisy(const Image& t, double sigma, double gain, std::mt19937_64* rng) {
  std::normal_distribution<double> normal;
  Image image = t;
  for (size_t k = 0; k < image.rgb.size(); ++k) {
    const bool left = (k / 3) % kWidth < kWidth / 2;
    image.rgb[k] = float(t.rgb[k] * ((left ? gain : 1.0) + sigma * normal(*rng)));
  }
  return image;
}

// E[(x - t)^2 / (t^2 + 0.01)] over the image for noise sigma and gain.
double expected(const Image& t, double sigma, double gain) {
  double sum = 0;
  for (size_t k = 0; k < t.rgb.size(); ++k) {
    const double r = t.rgb[k], left = (k / 3) % kWidth < kWidth / 2;
    const double bias = left ? (gain - 1) * r : 0.0;
    sum += (sigma * sigma * r * r + bias * bias) / (r * r + 0.01);
  }
  return sum / double(t.rgb.size());
}

TEST(CrossEstimate, RecoversTheErrorsOfThreeIndependentImages) {
  // e_a's estimate is the mean of (a - b)(a - c) / (r^2 + 0.01): with errors of variances
  // va, vb, vc its terms have variance (va + vb)(va + vc) + va^2, about 5.4e-4 for the least
  // noisy image here (va = 0.0025, vb = 0.01, vc = 0.04), so over 60000 values the estimate's
  // standard deviation is 9.5e-5, 3.8% of 0.0025 (1.1% and 0.6% for the others). r, the
  // images' mean over a pixel's 8 neighbours, raises r^2 by its variance, (va + vb + vc) / 72 =
  // 0.07% of it, and bends with the image by about as much. Hence 4 standard deviations and
  // 0.5%. (With the pixel's own mean for r, the noisiest image came out 4% high at every seed:
  // its noise in the denominator.)
  const Image t = truth();
  const double sigmas[3] = {0.05, 0.1, 0.2};
  const double tolerance[3] = {4 * 0.038 + 0.005, 4 * 0.011 + 0.005, 4 * 0.006 + 0.005};
  for (uint32_t seed : {1u, 2u, 3u}) {
    std::mt19937_64 rng(seed);
    std::vector<Image> images;
    for (double s : sigmas) images.push_back(noisy(t, s, 1.0, &rng));
    const std::vector<double> e = crossEstimates({&images[0], &images[1], &images[2]});
    ASSERT_EQ(e.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      const double want = expected(t, sigmas[i], 1.0);
      EXPECT_NEAR(e[i] / want, 1.0, tolerance[i]) << "image " << i << ", seed " << seed;
    }
  }
}

TEST(CrossEstimate, SeesLightThatOneImageMisses) {
  // The second image has little noise but 20% too little light in its left half, as a pilot
  // that has not yet found a light's rare paths: its error is mostly that deficit, 0.02, which
  // the hat finds; the spread of its own noise would say 1e-4.
  const Image t = truth();
  std::mt19937_64 rng(7);
  const Image a = noisy(t, 0.1, 1.0, &rng), b = noisy(t, 0.01, 0.8, &rng),
              c = noisy(t, 0.1, 1.0, &rng), d = noisy(t, 0.15, 1.0, &rng);
  const std::vector<double> e = crossEstimates({&a, &b, &c, &d});
  ASSERT_EQ(e.size(), 4u);
  const double want = expected(t, 0.01, 0.8);
  EXPECT_GT(want, 100 * expected(t, 0.01, 1.0));
  // The hat's terms, (b - a)(b - c), carry the deficit itself; only its denominator takes r
  // from the images' mean, which the deficit lowers by a quarter of itself (5%) in the left
  // half, where all of b's error is: 1 / 0.95^2 = 1.108 of the truth's ratio.
  EXPECT_NEAR(e[1] / want, 1.108, 0.05);
  // The others keep their own errors (their noise, over the same denominator: half the image
  // 1.108 of the truth's, so 1.054; the estimate's own deviation is 1.1%).
  EXPECT_NEAR(e[0] / expected(t, 0.1, 1.0), 1.054, 0.05);
}

TEST(CrossEstimate, NeedsThreeImagesOfOneSize) {
  const Image a(4, 4), b(4, 4), c(4, 4), small(2, 2);
  EXPECT_TRUE(crossEstimates({&a, &b}).empty());
  EXPECT_TRUE(crossEstimates({&a, &b, &small}).empty());
  EXPECT_EQ(crossEstimates({&a, &b, &c}).size(), 3u);
}

}  // namespace
}  // namespace farm
