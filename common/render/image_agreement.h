#pragma once
// Test code only: whether two estimators of the same image agree, each rendered twice with
// different seeds, and their means over more renders (the statistical tests of thin_lens_test
// and environment_test), and one
// image's mean and its standard error from the spread of its pixels (furnace_test).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

#include "common/film/image.h"

namespace farm {

// Two estimators of the same image, each rendered twice with different seeds. Over the image,
// the squared differences of their averages are explained by their variance (each pixel's from
// its pair): the ratio of the sums is one for unbiased estimators, and a biased one (a lens
// point missed, a density from the lens's centre) adds its squared bias. Their means differ by
// noise of standard error `se`, to which the second's relative error zRel (its Z's) is added.
struct Agreement {
  double meanA = 0, meanB = 0, se = 0, ratio = 0;
};
inline Agreement compare(const Image (&a)[2], const Image (&b)[2], double zRel = 0) {
  const size_t n = a[0].rgb.size();
  double sum[2] = {0, 0}, var = 0, squared = 0;
  for (size_t i = 0; i < n; ++i) {
    const double ma = 0.5 * (a[0].rgb[i] + a[1].rgb[i]), mb = 0.5 * (b[0].rgb[i] + b[1].rgb[i]);
    const double da = a[0].rgb[i] - a[1].rgb[i], db = b[0].rgb[i] - b[1].rgb[i];
    var += (da * da + db * db) / 4;
    sum[0] += ma, sum[1] += mb;
    squared += (ma - mb) * (ma - mb);
  }
  Agreement g;
  g.meanA = sum[0] / double(n);
  g.meanB = sum[1] / double(n);
  g.se = std::hypot(std::sqrt(var) / double(n), g.meanB * zRel);
  g.ratio = squared / var;
  return g;
}

// Two estimators of the same image, each rendered independently several times (different
// seeds, each render with its own bootstrap): the image means' averages and their standard
// errors from the spread of the renders' means. Unlike compare()'s pixel-wise error, this holds
// for estimators whose pixels are correlated (a chain's, ERPT's deposits around a seed, a Z
// that scales a whole render): every source of a render's error is in its mean's spread.
struct MeanAgreement {
  double meanA = 0, meanB = 0, seA = 0, seB = 0;
  double se() const { return std::hypot(seA, seB); }
};
inline MeanAgreement compareMeans(const std::vector<Image>& a, const std::vector<Image>& b) {
  auto stats = [](const std::vector<Image>& renders, double* mean, double* se) {
    double s = 0, s2 = 0;
    for (const Image& img : renders) {
      double m = 0;
      for (float v : img.rgb) m += v;
      m /= double(img.rgb.size());
      s += m;
      s2 += m * m;
    }
    const double k = double(renders.size());
    *mean = s / k;
    *se = k > 1 ? std::sqrt(std::max(0.0, (s2 - k * *mean * *mean) / (k - 1)) / k) : INFINITY;
  };
  MeanAgreement g;
  stats(a, &g.meanA, &g.seA);
  stats(b, &g.meanB, &g.seB);
  return g;
}

// A chain's renders against path tracing's (`what` names them in the output): their means within
// 4 standard errors of compareMeans() (with 15 or more degrees of freedom per side, |t| > 4 has
// probability 0.1% or less), and the first two renders' squared differences explained by their
// variance, pixel by pixel (compare()).
inline void expectRendersAgree(const std::string& what, const std::vector<Image>& pt,
                               const std::vector<Image>& chain) {
  const MeanAgreement m = compareMeans(pt, chain);
  EXPECT_NEAR(m.meanA, m.meanB, 4 * m.se()) << what;
  const Image firstPt[2] = {pt[0], pt[1]}, firstChain[2] = {chain[0], chain[1]};
  const Agreement g = compare(firstPt, firstChain);
  EXPECT_LT(g.ratio, 1.5) << what;
  std::printf(
      "%s: means pt %.5f +- %.5f, chain %.5f +- %.5f (%zu and %zu renders, %.2f standard errors "
      "apart); squared differences over variance %.3f\n",
      what.c_str(), m.meanA, m.seA, m.meanB, m.seB, pt.size(), chain.size(),
      (m.meanB - m.meanA) / m.se(), g.ratio);
}

// The mean of each channel over the image, and its standard error taken from the pixels'
// spread: right where pixels are independent estimates (PT, BDPT), an approximation for chains.
struct PixelStats {
  double mean[3] = {0, 0, 0};
  double stdError[3] = {0, 0, 0};
};
inline PixelStats pixelStats(const Image& img) {
  PixelStats st;
  const size_t n = size_t(img.width) * img.height;
  for (int c = 0; c < 3; ++c) {
    double s = 0, s2 = 0;
    for (size_t i = 0; i < n; ++i) {
      const double v = img.rgb[3 * i + c];
      s += v;
      s2 += v * v;
    }
    st.mean[c] = s / double(n);
    st.stdError[c] = std::sqrt(std::max(0.0, s2 / double(n) - st.mean[c] * st.mean[c]) / double(n));
  }
  return st;
}

}  // namespace farm
