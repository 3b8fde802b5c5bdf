// The probabilities light sampling realizes are the ones its densities (and so the MIS weights)
// assume: a light in proportion to its power, a triangle of a mesh light in proportion to its
// area, even for 10^5 triangles whose areas span ten decades; and the start densities built from
// them integrate to one over every kind of light.
#include "common/scene/lights.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/scene/scene.h"
#include "common/scene/stiff_scenes.h"
#include "common/scene/test_scenes.h"

namespace farm {
namespace {

double triangleAreaOf(const ShapeDescription& s, size_t t) {
  const Vec3f &a = s.positions[s.indices[3 * t]], &b = s.positions[s.indices[3 * t + 1]],
              &c = s.positions[s.indices[3 * t + 2]];
  const double e1[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
  const double e2[3] = {double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
  const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
  return 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

TEST(LightSampling, ProbabilitiesAreTheDensitiesOnes) {
  SceneDescription d = stiff::tessellatedFurnace(8, 1042, 4);
  Scene scene(d);
  ASSERT_EQ(scene.lights().size(), d.shapes.size());
  double pickSum = 0, minShare = 1;
  for (int l = 0; l < int(scene.lights().size()); ++l) {
    const Light& light = scene.lights()[size_t(l)];
    const ShapeDescription& s = d.shapes[size_t(light.shape)];
    // The light: its CDF's step is the pdf that Lights::pick returns and MIS uses.
    const double pick = scene.lights().pickProbability(l);
    EXPECT_NEAR(pick, scene.lights().pickPdf(l), 1e-6 * pick) << "light " << l;
    pickSum += pick;
    double area = 0;
    for (size_t t = 0; t < s.indices.size() / 3; ++t) area += triangleAreaOf(s, t);
    EXPECT_NEAR(light.area, area, 1e-6 * area);
    // Each triangle: its CDF's step is its share of the area (density 1 / area).
    for (size_t t = 0; t < s.indices.size() / 3; ++t) {
      const double share = triangleAreaOf(s, t) / area;
      minShare = std::min(minShare, share);
      ASSERT_NEAR(scene.lights().trianglePickProbability(l, uint32_t(t)), share, 1e-6 * share)
          << "light " << l << " triangle " << t;
    }
  }
  EXPECT_NEAR(pickSum, 1.0, 1e-9);
  EXPECT_LT(minShare, 1e-8);  // the test covers shares below float's resolution
}

// The start density every estimator's MIS takes from the scene is the pick's probability times
// the position's density: 1 / area on an area light, the delta's coefficient 1 on a point light,
// the direction's density on the environment (a constant one: 1 / 4 pi); so over all lights
// it integrates to one.
TEST(LightSampling, StartDensityIsThePickTimesThePositionsDensity) {
  SceneDescription d = whiteFurnace(0.5f, 5);
  PointLightDescription point;
  point.position = Vec3f(0.2f, 0.1f, 0.3f);
  point.intensity = Spectrum(3.0f);
  d.pointLights.push_back(point);
  d.environment.present = true;
  d.environment.scale = Spectrum(0.25f);
  Scene scene(d);
  double total = 0;
  int kinds[3] = {0, 0, 0};
  for (int l = 0; l < int(scene.lights().size()); ++l) {
    const Light& light = scene.lights()[size_t(l)];
    const double pick = scene.lights().pickProbability(l);
    const Vec3f w = normalize(Vec3f(0.3f, -0.4f, 0.5f));
    const double density = scene.lights().startDensity(l, w);
    if (light.isEnvironment()) {
      ++kinds[0];
      EXPECT_NEAR(density, pick / (4 * kPi), 1e-6 * density);
      total += density * 4 * kPi;
    } else if (light.isPoint()) {
      ++kinds[1];
      EXPECT_NEAR(density, pick, 1e-6 * density);
      total += density;
    } else {
      ++kinds[2];
      EXPECT_NEAR(density * light.area, pick, 1e-6 * pick);
      total += density * light.area;
    }
  }
  EXPECT_EQ(kinds[0], 1);
  EXPECT_EQ(kinds[1], 1);
  EXPECT_GE(kinds[2], 1);
  EXPECT_NEAR(total, 1.0, 1e-6);
  EXPECT_EQ(scene.lights().startDensity(-1), 0.0);
}

// pickTriangle picks each triangle of a mesh light by its area, taken here from the geometry:
// the number at the middle of a triangle's share of [0, 1) picks it, for every triangle whose
// share float numbers can resolve (here down to 1e-6; the shares span ten decades), and numbers
// spread evenly fall on each in its share. A CDF scaled by 1.1, or built from other areas, fails.
TEST(LightSampling, PickTriangleRealizesTheAreaShares) {
  SceneDescription d = stiff::tessellatedFurnace(8, 10, 4);
  Scene scene(d);
  const Lights& lights = scene.lights();
  constexpr int kNumbers = 1 << 16;
  int resolved = 0;
  for (int l = 0; l < int(lights.size()); ++l) {
    const ShapeDescription& s = d.shapes[size_t(lights[l].shape)];
    const size_t triangles = s.indices.size() / 3;
    double area = 0;
    for (size_t t = 0; t < triangles; ++t) area += triangleAreaOf(s, t);
    double below = 0;
    for (size_t t = 0; t < triangles; ++t) {
      const double share = triangleAreaOf(s, t) / area;
      if (share > 1e-6) {
        EXPECT_EQ(lights.pickTriangle(l, float(below + share / 2)), uint32_t(t))
            << "light " << l << " triangle " << t << " of share " << share;
        ++resolved;
      }
      below += share;
    }
    std::vector<int> hits(triangles, 0);
    for (int k = 0; k < kNumbers; ++k) {
      const uint32_t t = lights.pickTriangle(l, (float(k) + 0.5f) / kNumbers);
      ASSERT_LT(t, triangles);
      ++hits[t];
    }
    for (size_t t = 0; t < triangles; ++t)
      EXPECT_NEAR(double(hits[t]) / kNumbers, triangleAreaOf(s, t) / area, 2.0 / kNumbers)
          << "light " << l << " triangle " << t;
  }
  EXPECT_GT(resolved, int(lights.size()) * 10);
}

}  // namespace
}  // namespace farm
