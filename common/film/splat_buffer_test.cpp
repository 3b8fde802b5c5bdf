#include "common/film/splat_buffer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/sampling/rng.h"

namespace farm {
namespace {

struct NamedFilter {
  std::string name;
  PixelFilter filter;
};

const NamedFilter kFilters[] = {
    {"box", {FilterType::Box, 0, 0}},
    {"tent", {FilterType::Tent, 0, 0}},
    {"gaussian r2 a2", {FilterType::Gaussian, 2, 2}},       // pbrt-v3's and Mitsuba's default
    {"gaussian r1.5 a2", {FilterType::Gaussian, 1.5f, 2}},  // pbrt-v4's default
    {"gaussian r3 a0.5", {FilterType::Gaussian, 3, 0.5f}},
};

double total(const SplatBuffer& film) {
  double sum = 0;
  for (size_t i = 0; i < film.data().size(); i += 3) sum += film.data()[i];
  return sum;
}

// A flush's splats are summed in double: 2^20 increments of 1e-8 onto a pixel holding 1 (each
// below half a float ulp of it) add up to 0.0105, which a float sum would drop entirely.
TEST(SplatBuffer, SumsSplatsInDouble) {
  SplatBuffer film(4, 4, {FilterType::Box, 0, 0});
  film.add({1.5f, 1.5f}, Spectrum(1.0f));
  for (int i = 0; i < (1 << 20); ++i) film.add({1.5f, 1.5f}, Spectrum(1e-8f));
  const double expected = 1.0 + double(1 << 20) * double(1e-8f);
  EXPECT_NEAR(film.data()[(1 * 4 + 1) * 3], expected, 1e-9);
  EXPECT_NEAR(film.data()[(1 * 4 + 1) * 3 + 2], expected, 1e-9);
}

// Away from the edges a splat's weights add up to one: its value is kept.
TEST(SplatBuffer, InteriorSplatsKeepTheirValue) {
  for (const NamedFilter& f : kFilters) {
    Rng rng(3, 1);
    for (int k = 0; k < 200; ++k) {
      SplatBuffer film(16, 16, f.filter);
      film.add({6 + 4 * rng.nextFloat(), 6 + 4 * rng.nextFloat()}, Spectrum(1.0f));
      EXPECT_NEAR(total(film), 1.0, 1e-5) << f.name;
    }
  }
}

// Gaussians that reach no pixel centre from some film points (radius under half a pixel) or
// underflow between centres (a huge alpha): the nearest pixel takes those splats, so every splat
// still counts once. The loaders refuse such filters; the film does not rely on it.
TEST(SplatBuffer, NarrowGaussiansStillKeepEverySplat) {
  for (PixelFilter f :
       {PixelFilter{FilterType::Gaussian, 0.3f, 2}, PixelFilter{FilterType::Gaussian, 2, 5000}}) {
    Rng rng(5, 3);
    for (int k = 0; k < 200; ++k) {
      SplatBuffer film(16, 16, f);
      film.add({6 + 4 * rng.nextFloat(), 6 + 4 * rng.nextFloat()}, Spectrum(1.0f));
      EXPECT_NEAR(total(film), 1.0, 1e-5) << f.radius << " " << f.alpha;
    }
  }
  // Not a number, or far away: nothing, and no undefined conversion.
  SplatBuffer film(4, 4, PixelFilter{FilterType::Gaussian, 2, 2});
  film.add({NAN, 1}, Spectrum(1.0f));
  film.add({1e30f, 1}, Spectrum(1.0f));
  EXPECT_EQ(total(film), 0.0);
}

// Splats at uniform film points: pixel j receives on average N / pixels times the share of its
// filter on the film (pixelFilterMassInside in x times in y), one inside and less near edges.
// What RenderJob::resolve divides by; a filter whose pixels did not integrate to one, or a wrong
// edge share, would leave a pattern or a rim. Tolerance: 4.5 standard errors from 16 batches.
TEST(SplatBuffer, EachPixelsFilterIntegratesToItsShareOfTheFilm) {
  const int w = 9, h = 7, batches = 16;
  const int64_t perBatch = 200000;
  for (const NamedFilter& f : kFilters) {
    std::vector<double> sum(size_t(w) * h, 0.0), sumSq(size_t(w) * h, 0.0);
    Rng rng(11, 2);
    for (int b = 0; b < batches; ++b) {
      SplatBuffer film(w, h, f.filter);
      for (int64_t k = 0; k < perBatch; ++k)
        film.add({w * rng.nextFloat(), h * rng.nextFloat()}, Spectrum(1.0f));
      for (int j = 0; j < w * h; ++j) {
        const double v = film.data()[size_t(3 * j)] / (double(perBatch) / (w * h));
        sum[size_t(j)] += v;
        sumSq[size_t(j)] += v * v;
      }
    }
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const size_t j = size_t(y) * w + x;
        const double mean = sum[j] / batches;
        const double se = std::sqrt((sumSq[j] / batches - mean * mean) / (batches - 1));
        const double expected =
            pixelFilterMassInside(f.filter, x, w) * pixelFilterMassInside(f.filter, y, h);
        EXPECT_NEAR(mean, expected, 4.5 * se + 1e-4) << f.name << " pixel " << x << ", " << y;
      }
    }
    // The edges lose what reaches past them: a gaussian of radius 2 more than the tent.
    if (f.filter.type != FilterType::Box) {
      EXPECT_LT(pixelFilterMassInside(f.filter, 0, w), 0.95) << f.name;
      EXPECT_EQ(pixelFilterMassInside(f.filter, w / 2, w), 1.0) << f.name;
    }
  }
}

}  // namespace
}  // namespace farm
