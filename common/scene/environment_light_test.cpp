// The environment's importance sampling against its own density and against uniform sampling
// (which shares nothing with it), and its lat-long frame against pbrt's.
#include "common/scene/environment_light.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "common/sampling/rng.h"
#include "common/sampling/warp.h"
#include "common/scene/test_scenes.h"

namespace farm {
namespace {

EnvironmentDescription skyDescription() {
  EnvironmentDescription d;
  d.present = true;
  d.image = latLongSky(10);
  d.scale = Spectrum(1.0f, 0.9f, 1.1f);
  d.toWorld = Matrix4::rotate(Vec3f(0.3f, 1.0f, 0.2f), 37);  // any rotation
  return d;
}

void expectSame(const Spectrum& a, const Spectrum& b, int line) {
  EXPECT_TRUE(a.x == b.x && a.y == b.y && a.z == b.z)
      << "line " << line << ": (" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x << ", "
      << b.y << ", " << b.z << ")";
}

struct Mean {
  double sum = 0, sum2 = 0;
  int n = 0;
  void add(double v) { sum += v, sum2 += v * v, ++n; }
  double mean() const { return sum / n; }
  double stdError() const { return std::sqrt(std::max(0.0, sum2 / n - mean() * mean()) / n); }
};

TEST(EnvironmentLight, DensityIntegratesToOneAndSamplesFollowIt) {
  EnvironmentLight light(skyDescription());
  Rng rng(5, 1);
  // The density's integral by the midpoint rule on a grid finer than the map's texels, in the
  // map's own (phi, theta) rotated to world space: exact up to the grid.
  const Matrix4 toWorld = skyDescription().toWorld;
  double pdfIntegral = 0;
  const int nPhi = 512, nTheta = 256;
  for (int j = 0; j < nTheta; ++j) {
    const double theta = kPi * (j + 0.5) / nTheta;
    for (int i = 0; i < nPhi; ++i) {
      const double phi = 2 * kPi * (i + 0.5) / nPhi;
      const Vec3f local(float(std::sin(theta) * std::cos(phi)),
                        float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
      pdfIntegral += light.pdf(normalize(toWorld.applyVector(local))) * std::sin(theta) *
                     (2 * kPi / nPhi) * (kPi / nTheta);
    }
  }
  EXPECT_NEAR(pdfIntegral, 1.0, 2e-3);
  // Over uniform directions (sampling that shares nothing with the light's): the luminance.
  Mean uniformLuminance;
  for (int i = 0; i < 400000; ++i) {
    const Vec3f w = squareToUniformSphere({rng.nextFloat(), rng.nextFloat()});
    uniformLuminance.add(4 * kPi * luminance(light.radiance(w)));
  }
  EXPECT_NEAR(uniformLuminance.mean(), light.luminanceIntegral(), 4 * uniformLuminance.stdError());
  // Over the light's own samples: the same luminance integral (a density that is not the
  // sampler's, even by 10%, shows here), with far less variance than uniform sampling.
  Mean importance;
  for (int i = 0; i < 100000; ++i) {
    float pdf;
    const Vec3f w = light.sample({rng.nextFloat(), rng.nextFloat()}, &pdf);
    ASSERT_GT(pdf, 0);
    EXPECT_NEAR(pdf, light.pdf(w), 1e-4f * pdf);
    importance.add(luminance(light.radiance(w)) / pdf);
  }
  EXPECT_NEAR(importance.mean(), light.luminanceIntegral(), 4 * importance.stdError());
  EXPECT_LT(importance.stdError() * 10, uniformLuminance.stdError());
  std::printf(
      "environment: integral of the density %.5f; luminance %.3f (own samples "
      "%.3f +- %.3f, uniform %.3f +- %.3f)\n",
      pdfIntegral, light.luminanceIntegral(), importance.mean(), importance.stdError(),
      uniformLuminance.mean(), uniformLuminance.stdError());
}

TEST(EnvironmentLight, MapsDirectionsAsPbrtDoes) {
  EnvironmentDescription d = skyDescription();
  d.toWorld = Matrix4::identity();
  d.scale = Spectrum(1.0f);
  EnvironmentLight light(d);
  const TextureImage& image = *d.image;
  // +z is the top row; phi = atan2(y, x) runs along the columns from +x.
  expectSame(light.radiance(Vec3f(0, 0, 1)), image.texel(0, 0), __LINE__);
  const float c = std::cos(0.05f), s = std::sin(0.05f);  // 0.05 rad off the horizon
  expectSame(light.radiance(Vec3f(c, 0.001f, s)), image.texel(0, 15), __LINE__);
  expectSame(light.radiance(Vec3f(0.001f, c, s)), image.texel(16, 15), __LINE__);
  expectSame(light.radiance(Vec3f(-c, -0.001f, -s)), image.texel(32, 16), __LINE__);
  // The sun: columns 10-11 (phi around 60 degrees), rows 5-6 (theta around 31 degrees).
  const float theta = kPi * 6 / 32, phi = 2 * kPi * 11 / 64;
  const Vec3f sun(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                  std::cos(theta));
  expectSame(light.radiance(sun), Spectrum(400, 350, 300), __LINE__);
}

TEST(EnvironmentLight, ConstantIsUniform) {
  EnvironmentDescription d;
  d.present = true;
  d.scale = Spectrum(1.0f, 0.5f, 2.0f);
  EnvironmentLight light(d);
  float pdf;
  const Vec3f w = light.sample({0.3f, 0.8f}, &pdf);
  EXPECT_NEAR(length(w), 1.0f, 1e-6f);
  EXPECT_FLOAT_EQ(pdf, 1 / (4 * kPi));
  EXPECT_FLOAT_EQ(light.pdf(Vec3f(0, 1, 0)), 1 / (4 * kPi));
  expectSame(light.radiance(w), d.scale, __LINE__);
  EXPECT_NEAR(light.luminanceIntegral(), 4 * kPi * luminance(d.scale), 1e-4);
}

}  // namespace
}  // namespace farm
