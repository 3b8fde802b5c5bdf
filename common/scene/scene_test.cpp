// The probabilities light sampling realizes are the ones its densities (and so the MIS weights)
// assume: a light in proportion to its power, a triangle of a mesh light in proportion to its
// area, even for 10^5 triangles whose areas span ten decades.
#include "common/scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/scene/stiff_scenes.h"

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
    const AreaLight& light = scene.lights()[size_t(l)];
    const ShapeDescription& s = d.shapes[size_t(light.shape)];
    // The light: its CDF's step is the pdf that pickLight returns and MIS uses.
    const double pick = scene.lightPickProbability(l);
    EXPECT_NEAR(pick, scene.lightPickPdf(l), 1e-6 * pick) << "light " << l;
    pickSum += pick;
    double area = 0;
    for (size_t t = 0; t < s.indices.size() / 3; ++t) area += triangleAreaOf(s, t);
    EXPECT_NEAR(light.area, area, 1e-6 * area);
    // Each triangle: its CDF's step is its share of the area (density 1 / area).
    for (size_t t = 0; t < s.indices.size() / 3; ++t) {
      const double share = triangleAreaOf(s, t) / area;
      minShare = std::min(minShare, share);
      ASSERT_NEAR(scene.trianglePickProbability(l, uint32_t(t)), share, 1e-6 * share)
          << "light " << l << " triangle " << t;
    }
  }
  EXPECT_NEAR(pickSum, 1.0, 1e-9);
  EXPECT_LT(minShare, 1e-8);  // the test covers shares below float's resolution
}

}  // namespace
}  // namespace farm
