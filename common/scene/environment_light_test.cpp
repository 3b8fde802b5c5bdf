// The environment's importance sampling against its own density and against uniform sampling
// (which shares nothing with it), and its lat-long frame against pbrt's.
#include "common/scene/environment_light.h"

#include <gtest/gtest.h>

#include <algorithm>
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

// pbrt's spherical direction: theta from +z, phi from +x towards +y.
Vec3f fromSpherical(float theta, float phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// The light in its own frame, at scale 1: radiance is then the map's texel.
EnvironmentDescription unrotated(EnvironmentDescription d) {
  d.toWorld = Matrix4::identity();
  d.scale = Spectrum(1.0f);
  return d;
}

struct Mean {
  double sum = 0, sum2 = 0;
  int n = 0;
  void add(double v) { sum += v, sum2 += v * v, ++n; }
  double mean() const { return sum / n; }
  double stdError() const { return std::sqrt(std::max(0.0, sum2 / n - mean() * mean()) / n); }
};

EnvironmentDescription equalAreaSkyDescription() {
  EnvironmentDescription d = skyDescription();
  d.image = equalAreaSky();
  d.mapping = EnvironmentDescription::Mapping::EqualArea;
  return d;
}

void expectDensityIntegratesToOneAndSamplesFollowIt(const EnvironmentDescription& description) {
  EnvironmentLight light(description);
  Rng rng(5, 1);
  // The density's integral by the midpoint rule on a (phi, theta) grid finer than the map's
  // texels, rotated to world space: exact up to the grid.
  const Matrix4 toWorld = description.toWorld;
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
  // (An equal-area map is sampled exactly in proportion to its luminance: its estimates are all
  // the integral, up to rounding.)
  EXPECT_NEAR(importance.mean(), light.luminanceIntegral(),
              4 * importance.stdError() + 1e-6 * light.luminanceIntegral());
  EXPECT_LT(importance.stdError() * 10, uniformLuminance.stdError());
  std::printf(
      "environment: integral of the density %.5f; luminance %.3f (own samples "
      "%.3f +- %.3f, uniform %.3f +- %.3f)\n",
      pdfIntegral, light.luminanceIntegral(), importance.mean(), importance.stdError(),
      uniformLuminance.mean(), uniformLuminance.stdError());
}

TEST(EnvironmentLight, DensityIntegratesToOneAndSamplesFollowIt) {
  expectDensityIntegratesToOneAndSamplesFollowIt(skyDescription());
}

TEST(EnvironmentLight, EqualAreaDensityIntegratesToOneAndSamplesFollowIt) {
  expectDensityIntegratesToOneAndSamplesFollowIt(equalAreaSkyDescription());
}

// Clarberg's map at points whose images are known: the square's centre is the zenith, the
// middles of its edges the horizon's +-x and +-y, its corners the nadir, the diamond's edge the
// horizon; the inverse takes each direction back; and uniform points of the square land
// uniformly on the sphere (equal areas: Archimedes' bands of equal height, halves in phi).
TEST(EqualAreaMap, KnownPointsInverseAndEqualAreas) {
  auto near = [](const Vec3f& a, const Vec3f& b) {
    EXPECT_NEAR(a.x, b.x, 1e-6f);
    EXPECT_NEAR(a.y, b.y, 1e-6f);
    EXPECT_NEAR(a.z, b.z, 1e-6f);
  };
  near(equalAreaSquareToSphere({0.5f, 0.5f}), {0, 0, 1});
  near(equalAreaSquareToSphere({1, 0.5f}), {1, 0, 0});
  near(equalAreaSquareToSphere({0, 0.5f}), {-1, 0, 0});
  near(equalAreaSquareToSphere({0.5f, 1}), {0, 1, 0});
  near(equalAreaSquareToSphere({0.5f, 0}), {0, -1, 0});
  for (Vec2f corner : {Vec2f(0, 0), Vec2f(1, 0), Vec2f(0, 1), Vec2f(1, 1)})
    near(equalAreaSquareToSphere(corner), {0, 0, -1});
  near(equalAreaSquareToSphere({0.75f, 0.75f}), {std::sqrt(0.5f), std::sqrt(0.5f), 0});
  // Halfway from the centre to the right edge's middle: r = 1/2, z = 3/4, on +x.
  near(equalAreaSquareToSphere({0.75f, 0.5f}), {std::sqrt(1 - 0.5625f), 0, 0.75f});
  Rng rng(3, 9);
  int bins[8] = {};
  const int n = 400000;
  for (int i = 0; i < n; ++i) {
    const Vec2f u(rng.nextFloat(), rng.nextFloat());
    const Vec3f w = equalAreaSquareToSphere(u);
    ASSERT_NEAR(length(w), 1.0f, 1e-5f);
    const Vec2f back = equalAreaSphereToSquare(w);
    ASSERT_NEAR(back.x, u.x, 2e-4f) << u.x << " " << u.y;
    ASSERT_NEAR(back.y, u.y, 2e-4f) << u.x << " " << u.y;
    const int band = std::min(3, int((w.z + 1) * 2));
    ++bins[2 * band + (w.y > 0 ? 1 : 0)];
  }
  // Each bin holds an eighth of the sphere: binomial counts within 4.5 standard deviations.
  const double sd = std::sqrt(n * (1.0 / 8) * (7.0 / 8));
  for (int b = 0; b < 8; ++b) EXPECT_NEAR(bins[b], n / 8.0, 4.5 * sd) << "bin " << b;
}

// The texel each direction reads in a 48 x 48 equal-area map: the zenith the centre texel, the
// horizon's +y the middle of the bottom row (v grows down the image, as pbrt-v4's), and a
// direction just below the horizon's -x the folded corner side: the left column's middle.
TEST(EnvironmentLight, EqualAreaMapsDirectionsAsPbrtV4Does) {
  const EnvironmentDescription d = unrotated(equalAreaSkyDescription());
  EnvironmentLight light(d);
  const TextureImage& image = *d.image;
  const float c = std::cos(0.05f), s = std::sin(0.05f);
  expectSame(light.radiance(Vec3f(0, 0, 1)), image.texel(24, 24), __LINE__);
  expectSame(light.radiance(Vec3f(0.001f, c, s)), image.texel(24, 47), __LINE__);
  expectSame(light.radiance(Vec3f(c, 0.001f, s)), image.texel(47, 24), __LINE__);
  expectSame(light.radiance(Vec3f(-c, -0.001f, -s)), image.texel(0, 23), __LINE__);
  // The sun, by its own direction.
  expectSame(light.radiance(fromSpherical(31 * kPi / 180, 60 * kPi / 180)), Spectrum(400, 350, 300),
             __LINE__);
}

TEST(EnvironmentLight, MapsDirectionsAsPbrtDoes) {
  const EnvironmentDescription d = unrotated(skyDescription());
  EnvironmentLight light(d);
  const TextureImage& image = *d.image;
  // +z is the top row; phi = atan2(y, x) runs along the columns from +x.
  expectSame(light.radiance(Vec3f(0, 0, 1)), image.texel(0, 0), __LINE__);
  const float c = std::cos(0.05f), s = std::sin(0.05f);  // 0.05 rad off the horizon
  expectSame(light.radiance(Vec3f(c, 0.001f, s)), image.texel(0, 15), __LINE__);
  expectSame(light.radiance(Vec3f(0.001f, c, s)), image.texel(16, 15), __LINE__);
  expectSame(light.radiance(Vec3f(-c, -0.001f, -s)), image.texel(32, 16), __LINE__);
  // The sun: columns 10-11 (phi around 60 degrees), rows 5-6 (theta around 31 degrees).
  expectSame(light.radiance(fromSpherical(kPi * 6 / 32, 2 * kPi * 11 / 64)),
             Spectrum(400, 350, 300), __LINE__);
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
