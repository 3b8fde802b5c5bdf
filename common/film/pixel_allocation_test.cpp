#include "common/film/pixel_allocation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace farm {
namespace {

// A 5x3 film in cells of 2: 3x2 cells, the right column one pixel wide, the bottom row one
// pixel high (areas 4 4 2 / 2 2 1, 15 pixels in all).
PixelAllocation clipped() {
  return PixelAllocation(5, 3, 2, {1, 2, 4, 0.5f, 1, 3}, {0, 1, 0, 1, 1, 0});
}

TEST(PixelAllocation, WeightsAreTheUniformFilmsDensityOverTheCells) {
  const PixelAllocation a = clipped();
  EXPECT_EQ(a.cellsX(), 3);
  EXPECT_EQ(a.cellsY(), 2);
  // sum d a = 1*4 + 2*4 + 4*2 + 0.5*2 + 1*2 + 3*1 = 26; weight of a cell 26 / (15 d), (1)
  const double total = 26, film = 15;
  const float d[] = {1, 2, 4, 0.5f, 1, 3};
  const int x0[] = {0, 2, 4, 0, 2, 4}, y0[] = {0, 0, 0, 2, 2, 2};
  for (int c = 0; c < 6; ++c) {
    // The middle of cell c: u0 between its cumulative probabilities.
    double before = 0;
    const double area[] = {4, 4, 2, 2, 2, 1};
    for (int k = 0; k < c; ++k) before += d[k] * area[k] / total;
    const double mid = before + 0.5 * d[c] * area[c] / total;
    const auto s = a.sampleFilm(float(mid), 0.5f, 0.5f);
    EXPECT_NEAR(s.cameraWeight, total / (film * d[c]), 1e-5) << c;
    EXPECT_GE(s.film.x, float(x0[c])) << c;
    EXPECT_GE(s.film.y, float(y0[c])) << c;
    EXPECT_EQ(s.bidirectional, a.bidirectional()[size_t(c)] != 0) << c;
  }
  // F_B = (2*4 + 0.5*2 + 1*2) / 26, to the grid of 2^-24 the cells' probabilities are on
  EXPECT_NEAR(a.lightTracingWeight(), 26.0 / 11.0, 26.0 / 11.0 * 0x1p-24 / (11.0 / 26.0) * 6);
  // r_c = 15 d_c / 26 over the film's 15 pixels: sum a_c r_c^2 / 15
  double concentration = 0;
  const double area[] = {4, 4, 2, 2, 2, 1};
  for (int c = 0; c < 6; ++c) concentration += area[c] * std::pow(film * d[c] / total, 2) / film;
  EXPECT_NEAR(a.concentration(), concentration, 1e-5);
  const PixelAllocation uniform(5, 3, 2, std::vector<float>(6, 2.0f), std::vector<uint8_t>(6, 0));
  EXPECT_NEAR(uniform.concentration(), 1.0, 1e-6);
}

// Drawn many times, each cell is picked with probability d_c a_c / sum d a and its points stay
// inside it; the camera weight averages to one over the draws (the uniform film's density over
// the allocation's), which is what keeps a camera estimate unbiased.
TEST(PixelAllocation, DrawsCellsInProportionToDensityTimesArea) {
  const PixelAllocation a = clipped();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const int n = 200000;
  std::vector<int> count(6, 0);
  double weightSum = 0;
  for (int i = 0; i < n; ++i) {
    const auto s = a.sampleFilm(u(rng), u(rng), u(rng));
    ASSERT_LT(s.film.x, 5.0f);
    ASSERT_LT(s.film.y, 3.0f);
    const int c = (int(s.film.y) / 2) * 3 + int(s.film.x) / 2;
    ++count[size_t(c)];
    weightSum += s.cameraWeight;
    ASSERT_EQ(s.bidirectional, a.bidirectionalAt(s.film));
  }
  const double p[] = {4 / 26.0, 8 / 26.0, 8 / 26.0, 1 / 26.0, 2 / 26.0, 3 / 26.0};
  for (int c = 0; c < 6; ++c) {
    const double se = std::sqrt(n * p[c] * (1 - p[c]));
    EXPECT_NEAR(count[size_t(c)], n * p[c], 4 * se) << c;
  }
  // E[weight] = sum_c P_c a_c / (A P_c) = 1; its spread over draws is below 2 here.
  EXPECT_NEAR(weightSum / n, 1.0, 4 * 2 / std::sqrt(double(n)));
}

// Over every u0 Rng::nextFloat can draw (the 2^24 multiples of 2^-24), each cell's share of
// the draws times its camera weight is its share of the film exactly: the weights are those
// of the probabilities the draws give, not of the unrounded densities. Cells a few grid points
// wide (densities 10^-4 of the largest, 4096 cells) are where rounding would show.
TEST(PixelAllocation, WeightsAreExactOverEveryDrawOfTheCell) {
  const int w = 64, h = 64;
  std::vector<float> density(size_t(w * h));
  std::vector<uint8_t> bidirectional(density.size());
  for (size_t c = 0; c < density.size(); ++c) {
    density[c] = c % 7 == 0 ? 1e-4f : float(1 + c % 13);
    bidirectional[c] = uint8_t(c % 3 == 0);
  }
  const PixelAllocation a(w, h, 1, density, bidirectional);
  std::vector<double> weightSum(density.size(), 0.0);
  std::vector<int64_t> count(density.size(), 0);
  const int64_t draws = int64_t(1) << 24;
  for (int64_t k = 0; k < draws; ++k) {
    const auto s = a.sampleFilm(float(k) * 0x1p-24f, 0.5f, 0.5f);
    const size_t c = size_t(int(s.film.y) * w + int(s.film.x));
    weightSum[c] += s.cameraWeight;
    ++count[c];
  }
  int64_t bidirectionalDraws = 0;
  for (size_t c = 0; c < density.size(); ++c) {
    ASSERT_GT(count[c], 0) << c;
    // float weights: exact to float rounding of one weight
    EXPECT_NEAR(weightSum[c] / double(draws), 1.0 / double(w * h), 2e-7 / double(w * h)) << c;
    if (bidirectional[c]) bidirectionalDraws += count[c];
  }
  EXPECT_NEAR(a.lightTracingWeight(), double(draws) / double(bidirectionalDraws), 1e-12);
}

TEST(PixelAllocation, EdgesOfTheUnitIntervalStayOnTheFilm) {
  const PixelAllocation a = clipped();
  const float one = std::nextafter(1.0f, 0.0f);
  for (float u0 : {0.0f, one}) {
    for (float u : {0.0f, one}) {
      const auto s = a.sampleFilm(u0, u, u);
      EXPECT_GE(s.film.x, 0.0f);
      EXPECT_LT(s.film.x, 5.0f);
      EXPECT_LT(s.film.y, 3.0f);
    }
  }
  // The last cell (1x1 at 4,2) keeps its points in itself up to rounding.
  const auto last = a.sampleFilm(one, one, one);
  EXPECT_GE(last.film.x, 4.0f);
  EXPECT_GE(last.film.y, 2.0f);
}

TEST(PixelAllocation, CellSizeKeepsTheCellCountBounded) {
  EXPECT_EQ(PixelAllocation::cellSizeFor(64, 64, 16384), 1);
  EXPECT_EQ(PixelAllocation::cellSizeFor(256, 256, 16384), 2);
  const int s = PixelAllocation::cellSizeFor(3840, 2160, 16384);
  EXPECT_LE(((3840 + s - 1) / s) * ((2160 + s - 1) / s), 16384);
  EXPECT_GT(((3840 + s - 2) / (s - 1)) * ((2160 + s - 2) / (s - 1)), 16384);
}

TEST(PixelAllocation, ByteFormRoundTripsAndRejectsWhatIsNotOne) {
  const PixelAllocation a = clipped();
  const PixelAllocation b = PixelAllocation::decode(a.encode());
  EXPECT_EQ(b.width(), 5);
  EXPECT_EQ(b.height(), 3);
  EXPECT_EQ(b.cellSize(), 2);
  EXPECT_EQ(b.density(), a.density());
  EXPECT_EQ(b.bidirectional(), a.bidirectional());

  const std::string bytes = a.encode();
  auto rejects = [](const std::string& form, const std::string& what) {
    try {
      PixelAllocation::decode(form);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("pixel allocation"), std::string::npos) << e.what();
    }
  };
  rejects("", "nothing");
  rejects(bytes.substr(0, bytes.size() - 1), "a cell short");
  rejects(bytes + "x", "a byte over");
  std::string wrongMagic = bytes;
  wrongMagic[0] ^= 1;
  rejects(wrongMagic, "another magic");
  std::string nanDensity = bytes;
  const float nan = std::nanf("");
  std::memcpy(&nanDensity[20], &nan, sizeof(float));  // the first density
  rejects(nanDensity, "a NaN density");
  std::string badEstimator = bytes;
  badEstimator.back() = 2;
  rejects(badEstimator, "estimator 2");
  std::string hugeFilm = bytes;
  const int32_t huge = 1 << 30;
  std::memcpy(&hugeFilm[8], &huge, sizeof(huge));
  rejects(hugeFilm, "a film of 2^30 pixels a side");
}

TEST(PixelAllocation, ConstructorNamesWhatIsWrong) {
  EXPECT_THROW(PixelAllocation(4, 4, 2, {1, 1, 1}, {0, 0, 0}), std::invalid_argument);
  EXPECT_THROW(PixelAllocation(4, 4, 2, {1, 1, 1, 0}, {0, 0, 0, 0}), std::invalid_argument);
  EXPECT_THROW(PixelAllocation(4, 4, 2, {1, 1, 1, -1}, {0, 0, 0, 0}), std::invalid_argument);
  EXPECT_THROW(PixelAllocation(4, 4, 2, {1, 1, 1, HUGE_VALF}, {0, 0, 0, 0}), std::invalid_argument);
  EXPECT_THROW(PixelAllocation(0, 4, 2, {}, {}), std::invalid_argument);
  EXPECT_THROW(PixelAllocation(4, 4, 0, {1}, {0}), std::invalid_argument);
  // No bidirectional cell: light tracing never counts.
  EXPECT_EQ(PixelAllocation(4, 4, 2, {1, 1, 1, 1}, {0, 0, 0, 0}).lightTracingWeight(), 0);
}

// A pilot's groups that differ on the left half of the film only: the samples go there in
// proportion to the square root of the relative error, the right half (no spread) keeps the
// floor's share, and the estimator is the one asked for.
TEST(PixelAllocation, ByErrorPutsTheSamplesWhereThePilotsGroupsDisagree) {
  const int w = 16, h = 8;
  std::vector<Image> groups(4, Image(w, h));
  for (size_t g = 0; g < groups.size(); ++g) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        // left: mean 1, spread growing to the left edge; right: 1 in every group
        const float spread = x < w / 2 ? 0.1f * float(w / 2 - x) : 0.0f;
        const float v = 1.0f + (g % 2 ? spread : -spread);
        groups[g].set(x, y, Spectrum(v, v, v));
      }
    }
  }
  const PixelAllocation a = PixelAllocation::byError(groups, true, 0, 0.01);
  EXPECT_EQ(a.cellSize(), 1);
  EXPECT_EQ(a.bidirectional(), std::vector<uint8_t>(size_t(w * h), 1));
  const std::vector<float>& d = a.density();
  double mean = 0;
  for (float v : d) mean += v / double(d.size());
  EXPECT_NEAR(mean, 1.0, 1e-5);
  // Variance of the mean of four: spread^2 * 4 / 12; relative over (1 + 0.01); density sqrt.
  auto error = [](double spread) { return spread * spread / 3 / 1.01; };
  double mean_error = 0;
  for (int x = 0; x < w / 2; ++x) mean_error += error(0.1 * (w / 2 - x)) / w;
  for (int x = 0; x < w / 2; ++x) {
    EXPECT_NEAR(d[size_t(x)] / d[size_t(x + 1)],
                std::sqrt(error(0.1 * (w / 2 - x)) /
                          std::max(error(0.1 * (w / 2 - x - 1)), 0.01 * mean_error)),
                1e-4)
        << x;
  }
  EXPECT_NEAR(d[size_t(w - 1)] / d[0], std::sqrt(0.01 * mean_error / error(0.1 * w / 2)), 1e-4);
  EXPECT_EQ(d[size_t(w - 1)], d[size_t(w / 2 + 1)]) << "the floor, alike on the right";
  EXPECT_EQ(PixelAllocation::byError(groups, false, 2).bidirectional(),
            std::vector<uint8_t>(size_t(w * h), 0));
  // Cells: the mean of their pixels' densities.
  const PixelAllocation coarse = PixelAllocation::byError(groups, true, 0, 0.01, 32);
  EXPECT_EQ(coarse.cellSize(), 2);
  EXPECT_THROW(PixelAllocation::byError({groups[0]}, true), std::invalid_argument);

  // The box: one pixel's spread reaches its 3x3 neighbourhood at radius 1, and no further.
  std::vector<Image> spike(2, Image(w, h));
  spike[0].set(5, 3, Spectrum(2, 2, 2));
  const PixelAllocation boxed = PixelAllocation::byError(spike, true, 1, 0.01);
  const std::vector<float>& b = boxed.density();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool near = std::abs(x - 5) <= 1 && std::abs(y - 3) <= 1;
      const float corner = b[size_t(2 * w + 4)];
      EXPECT_EQ(b[size_t(y * w + x)], near ? corner : b[0]) << x << "," << y;
    }
  }
  EXPECT_GT(b[size_t(2 * w + 4)], 5 * b[0]);
}

}  // namespace
}  // namespace farm
