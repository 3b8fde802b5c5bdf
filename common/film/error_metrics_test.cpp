#include "common/film/error_metrics.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <regex>
#include <string>

#include "common/film/image.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

const std::string kShared = FARM_SHARED_DIR;

Image loadReference(const std::string& name) {
  Image img;
  std::string error;
  EXPECT_TRUE(readExr(kShared + "/references/" + name, &img, &error)) << error;
  return img;
}

Image uniform(int w, int h, const Spectrum& s) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.set(x, y, s);
  return img;
}

TEST(ErrorMetricsTest, ReferenceAgainstItselfIsZero) {
  Image ref = loadReference("cornell-box-256.exr");
  ErrorMetrics m;
  std::string error;
  ASSERT_TRUE(compareImages(ref, ref, &m, &error)) << error;
  EXPECT_EQ(m.rmse, 0);
  EXPECT_EQ(m.relMse, 0);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(m.meanDeviation[c], 0);
    EXPECT_EQ(m.mean[c], m.referenceMean[c]);
    EXPECT_GT(m.mean[c], 0);
  }
  EXPECT_EQ(m.nonFinite, 0);
  EXPECT_EQ(m.negative, 0);
}

TEST(ErrorMetricsTest, HandComputedTwoPixels) {
  // Reference: pixel 0 = (1, 1, 1), pixel 1 = 0. The six sorted values 0 0 0 1 1 1 put numpy's
  // 99.9th percentile at index 4.995, between two ones: the cap is 1.
  Image ref(2, 1);
  ref.set(0, 0, Spectrum(1.0f));
  Image twice(2, 1);
  twice.set(0, 0, Spectrum(2.0f));
  ErrorMetrics m;
  std::string error;
  ASSERT_TRUE(compareImages(twice, ref, &m, &error)) << error;
  // Three of six channel values differ by 1: mean square 1/2; relative 1 / (1 + 0.01) each.
  EXPECT_DOUBLE_EQ(m.rmse, std::sqrt(0.5));
  EXPECT_DOUBLE_EQ(m.relMse, 0.5 / 1.01);
  for (int c = 0; c < 3; ++c) {
    EXPECT_DOUBLE_EQ(m.mean[c], 0.5);  // min(2, cap 1) and 0, averaged
    EXPECT_DOUBLE_EQ(m.referenceMean[c], 0.5);
    EXPECT_DOUBLE_EQ(m.meanDeviation[c], 0);
  }
  Image half(2, 1);
  half.set(0, 0, Spectrum(0.5f));
  ASSERT_TRUE(compareImages(half, ref, &m, &error)) << error;
  EXPECT_DOUBLE_EQ(m.rmse, std::sqrt(0.125));
  EXPECT_DOUBLE_EQ(m.relMse, 0.125 / 1.01);
  for (int c = 0; c < 3; ++c) {
    EXPECT_DOUBLE_EQ(m.mean[c], 0.25);
    EXPECT_DOUBLE_EQ(m.meanDeviation[c], 0.5);
  }
}

TEST(ErrorMetricsTest, ScaledReferenceMatchesDirectSums) {
  Image ref = loadReference("veach-mis-320.exr");
  Image scaled = ref;
  for (float& v : scaled.rgb) v *= 1.5f;
  ErrorMetrics m;
  std::string error;
  ASSERT_TRUE(compareImages(scaled, ref, &m, &error)) << error;
  double sq = 0, rel = 0;
  for (size_t i = 0; i < ref.rgb.size(); ++i) {
    double r = ref.rgb[i], d = double(scaled.rgb[i]) - r;
    sq += d * d;
    rel += d * d / (r * r + 0.01);
  }
  double n = double(ref.rgb.size());
  EXPECT_NEAR(m.rmse, std::sqrt(sq / n), 1e-12 * std::sqrt(sq / n));
  EXPECT_NEAR(m.relMse, rel / n, 1e-12 * rel / n);
  EXPECT_GT(m.relMse, 0);
}

TEST(ErrorMetricsTest, PercentileCapIsNumpyLinear) {
  // Values 0 .. 2999: numpy.percentile(v, 99.9) = 2999 * 0.999 = 2996.001. An image far above the
  // cap has the cap as its capped mean.
  Image ref(1000, 1);
  for (int i = 0; i < 3000; ++i) ref.rgb[i] = float(i);
  Image bright = uniform(1000, 1, Spectrum(1e9f));
  ErrorMetrics m;
  std::string error;
  ASSERT_TRUE(compareImages(bright, ref, &m, &error)) << error;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(m.mean[c], 2996.001, 1e-9);
  // A black reference: the cap's floor of 1e-6.
  Image black(4, 4);
  ASSERT_TRUE(compareImages(uniform(4, 4, Spectrum(1.0f)), black, &m, &error)) << error;
  for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(m.mean[c], 1e-6);
}

TEST(ErrorMetricsTest, CountsAndSizeMismatch) {
  Image ref = uniform(3, 2, Spectrum(0.5f));
  Image img = ref;
  img.rgb[0] = -1.0f;
  img.rgb[1] = std::numeric_limits<float>::quiet_NaN();
  img.rgb[2] = std::numeric_limits<float>::infinity();
  img.rgb[5] = -0.25f;
  ErrorMetrics m;
  std::string error;
  ASSERT_TRUE(compareImages(img, ref, &m, &error)) << error;
  EXPECT_EQ(m.nonFinite, 2);
  EXPECT_EQ(m.negative, 2);
  EXPECT_TRUE(std::isnan(m.rmse));  // as numpy: no silent filtering
  EXPECT_FALSE(compareImages(Image(3, 3), ref, &m, &error));
  EXPECT_NE(error.find("size"), std::string::npos) << error;
}

// ---- Cross-check against the project's reference tool ----

bool pythonToolAvailable() {
  return std::system("/usr/bin/python3 -c 'import numpy, OpenImageIO' >/dev/null 2>&1") == 0;
}

std::string run(const std::string& command) {
  std::string out;
  FILE* p = popen(command.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  pclose(p);
  return out;
}

double field(const std::string& out, const std::string& name) {
  std::smatch match;
  std::regex re(name + " ([-+0-9.eEinfa]+)");
  if (!std::regex_search(out, match, re)) return std::numeric_limits<double>::quiet_NaN();
  return std::stod(match[1]);
}

TEST(ErrorMetricsTest, AgreesWithImgcmpPy) {
  if (!pythonToolAvailable()) GTEST_SKIP() << "python3 with numpy and OpenImageIO not available";
  const std::string tool = kShared + "/tools/imgcmp.py";
  const std::string refPath = kShared + "/references/water-caustic-256.exr";
  Image ref = loadReference("water-caustic-256.exr");
  // A deterministic perturbation: relative noise, an offset, some negatives.
  Image img = ref;
  for (size_t i = 0; i < img.rgb.size(); ++i)
    img.rgb[i] = float(img.rgb[i] * (1.0 + 0.3 * std::sin(0.731 * double(i))) +
                       0.02 * std::cos(1.37 * double(i)));
  std::string pattern = (fs::temp_directory_path() / "imgcmp_XXXXXX").string();
  ASSERT_NE(mkdtemp(pattern.data()), nullptr);
  const std::string imgPath = pattern + "/perturbed.exr";
  std::string error;
  ASSERT_TRUE(writeExr(imgPath, img, {}, &error)) << error;
  ErrorMetrics m;
  ASSERT_TRUE(compareImages(img, ref, &m, &error)) << error;

  // The tool as it is, printing 4 significant digits: agree to its rounding.
  std::string out = run("/usr/bin/python3 " + tool + " " + imgPath + " " + refPath + " 2>&1");
  double rmse = field(out, "rmse"), relmse = field(out, "relmse");
  ASSERT_TRUE(std::isfinite(rmse) && std::isfinite(relmse)) << out;
  EXPECT_NEAR(m.rmse, rmse, 6e-4 * rmse) << out;
  EXPECT_NEAR(m.relMse, relmse, 6e-4 * relmse) << out;
  EXPECT_NE(out.find("negative " + std::to_string(m.negative)), std::string::npos) << out;

  // The same tool's code with full-precision output, for a 1e-4 relative comparison.
  const std::string precise =
      "import sys; src = open(sys.argv[1]).read().replace(':.4g}', ':.17g}'); "
      "sys.argv = sys.argv[1:]; exec(compile(src, sys.argv[0], 'exec'))";
  out = run("/usr/bin/python3 -c \"" + precise + "\" " + tool + " " + imgPath + " " + refPath +
            " 2>&1");
  rmse = field(out, "rmse");
  relmse = field(out, "relmse");
  ASSERT_TRUE(std::isfinite(rmse) && std::isfinite(relmse)) << out;
  EXPECT_NEAR(m.rmse, rmse, 1e-4 * rmse) << out;
  EXPECT_NEAR(m.relMse, relmse, 1e-4 * relmse) << out;
  // Capped means appear rounded to 4 decimals.
  std::smatch match;
  ASSERT_TRUE(std::regex_search(out, match, std::regex(R"(means \[([^\]]*)\] ref \[([^\]]*)\])")))
      << out;
  double xm[3], rm[3];
  ASSERT_EQ(sscanf(match[1].str().c_str(), "%lf, %lf, %lf", &xm[0], &xm[1], &xm[2]), 3);
  ASSERT_EQ(sscanf(match[2].str().c_str(), "%lf, %lf, %lf", &rm[0], &rm[1], &rm[2]), 3);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(m.mean[c], xm[c], 5.1e-5) << out;
    EXPECT_NEAR(m.referenceMean[c], rm[c], 5.1e-5) << out;
  }
  std::error_code ec;
  fs::remove_all(pattern, ec);
}

}  // namespace
}  // namespace farm
