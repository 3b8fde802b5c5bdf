// Point and spot lights: each format's falloff at points where it has a known value, and the
// emission directions against their density (which light subpaths and MIS rely on).
#include "common/scene/point_light.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/sampling/rng.h"

namespace farm {
namespace {

PointLightDescription spot(PointLightDescription::Falloff falloff) {
  PointLightDescription d;
  d.spot = true;
  d.direction = normalize(Vec3f(0.3f, -1, 0.2f));
  d.intensity = Spectrum(2, 1, 4);
  d.cosFalloffStart = std::cos(10 * kPi / 180);
  d.cosTotalWidth = std::cos(30 * kPi / 180);
  d.falloff = falloff;
  return d;
}

// A direction at `degrees` from the spot's axis.
Vec3f offAxis(const PointLightDescription& d, float degrees) {
  const Frame f(d.direction);
  const float a = degrees * kPi / 180;
  return f.toWorld(Vec3f(std::sin(a), 0, std::cos(a)));
}

TEST(PointLight, FalloffsOfEachFormat) {
  using F = PointLightDescription::Falloff;
  // Halfway between the two cosines: pbrt-v3's fourth power gives 1/16, v4's smoothstep 1/2.
  const float halfwayCos = 0.5f * (std::cos(10 * kPi / 180) + std::cos(30 * kPi / 180));
  const float halfwayDegrees = std::acos(halfwayCos) * 180 / kPi;
  for (auto [falloff, expected] :
       {std::pair{F::PbrtV3Quartic, 0.0625f}, std::pair{F::PbrtV4Smoothstep, 0.5f}}) {
    const PointLightDescription d = spot(falloff);
    PointLight light(d);
    EXPECT_NEAR(light.intensity(offAxis(d, halfwayDegrees)).x, 2 * expected, 1e-4f);
    EXPECT_FLOAT_EQ(light.intensity(offAxis(d, 5)).z, 4);
    EXPECT_FLOAT_EQ(light.intensity(offAxis(d, 31)).y, 0);
  }
  // Mitsuba's is linear in the angle: half at 20 degrees.
  const PointLightDescription d = spot(F::MitsubaLinearAngle);
  EXPECT_NEAR(PointLight(d).intensity(offAxis(d, 20)).x, 1.0f, 1e-4f);
  EXPECT_NEAR(PointLight(d).intensity(offAxis(d, 25)).x, 0.5f, 1e-4f);
  // A point light shines alike everywhere.
  PointLightDescription point;
  point.intensity = Spectrum(3);
  EXPECT_FLOAT_EQ(PointLight(point).intensity(Vec3f(0, 0, -1)).x, 3);
  EXPECT_NEAR(PointLight(point).power(), 4 * kPi * 3, 1e-4);
}

TEST(PointLight, DirectionsFollowTheirDensity) {
  for (bool isSpot : {false, true}) {
    PointLightDescription d = spot(PointLightDescription::Falloff::PbrtV3Quartic);
    d.spot = isSpot;
    PointLight light(d);
    // The integral of the intensity's luminance over the sphere by the midpoint rule about the
    // axis, and by the light's own samples.
    const Frame f(d.direction);
    double grid = 0;
    const int n = 2000;
    for (int j = 0; j < n; ++j) {
      const double theta = M_PI * (j + 0.5) / n;
      for (int i = 0; i < 8; ++i) {  // the falloff does not depend on phi
        const double phi = 2 * M_PI * (i + 0.5) / 8;
        const Vec3f w =
            f.toWorld(Vec3f(float(std::sin(theta) * std::cos(phi)),
                            float(std::sin(theta) * std::sin(phi)), float(std::cos(theta))));
        grid += luminance(light.intensity(w)) * std::sin(theta) * (M_PI / n) * (2 * M_PI / 8);
      }
    }
    Rng rng(3, 1);
    double sum = 0, sum2 = 0;
    const int samples = 200000;
    for (int k = 0; k < samples; ++k) {
      float pdf;
      const Vec3f w = light.sampleDirection({rng.nextFloat(), rng.nextFloat()}, &pdf);
      ASSERT_GT(pdf, 0);
      EXPECT_FLOAT_EQ(pdf, light.directionPdf(w));
      const double v = luminance(light.intensity(w)) / pdf;
      sum += v;
      sum2 += v * v;
    }
    const double mean = sum / samples;
    const double se = std::sqrt(std::max(0.0, sum2 / samples - mean * mean) / samples);
    EXPECT_NEAR(mean, grid, 4 * se + 1e-4 * grid) << (isSpot ? "spot" : "point");
  }
}

}  // namespace
}  // namespace farm
