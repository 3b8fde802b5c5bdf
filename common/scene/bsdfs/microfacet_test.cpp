// The microfacet distributions against their defining identities, by quadrature: the projected
// areas of the facets make up the macro surface's, \int D(m) cos(theta_m) dm = 1 (Walter et al.
// 2007, eq. 4), and what Smith's shadowing leaves of them seen from v is v's projection,
// \int G1(v, m) max(0, v.m) D(m) dm = v.z (eq. 7); sample()'s density integrates to one.
#include "common/scene/bsdfs/microfacet.h"

#include <gtest/gtest.h>

#include <cmath>

namespace farm {
namespace {

// \int over the upper hemisphere of f(m), by the midpoint rule in (cos theta, phi), finely
// near the pole where narrow lobes live (cos theta = 1 - t^4).
template <typename F>
double hemisphere(F&& f, int nTheta = 4000, int nPhi = 64) {
  double sum = 0;
  for (int i = 0; i < nTheta; ++i) {
    const double t = (i + 0.5) / nTheta, cosTheta = 1 - std::pow(t, 4);
    const double dCos = 4 * std::pow(t, 3) / nTheta;
    const double sinTheta = std::sqrt(std::max(0.0, 1 - cosTheta * cosTheta));
    for (int j = 0; j < nPhi; ++j) {
      const double phi = 2 * kPi * (j + 0.5) / nPhi;
      const Vec3f m(float(sinTheta * std::cos(phi)), float(sinTheta * std::sin(phi)),
                    float(cosTheta));
      sum += f(m) * dCos * 2 * kPi / nPhi;
    }
  }
  return sum;
}

TEST(Microfacet, ProjectedAreasAddUp) {
  for (auto dist : {MicrofacetDistribution::Beckmann, MicrofacetDistribution::GGX})
    for (float alpha : {0.02f, 0.2f, 0.7f}) {
      const Microfacet facets{dist, alpha};
      EXPECT_NEAR(hemisphere([&](const Vec3f& m) { return facets.D(m) * m.z; }), 1.0, 5e-3)
          << int(dist) << " " << alpha;
      for (float cosV : {0.2f, 0.6f, 1.0f}) {
        const Vec3f v(std::sqrt(1 - cosV * cosV), 0, cosV);
        const double seen = hemisphere([&](const Vec3f& m) {
          return facets.G1(v, m) * std::max(0.0f, dot(v, m)) * facets.D(m);
        });
        // Beckmann's G1 is a rational fit to Smith's (eq. 27): within about 1%.
        EXPECT_NEAR(seen, cosV, (dist == MicrofacetDistribution::GGX ? 5e-3 : 1.5e-2) * cosV)
            << int(dist) << " " << alpha << " " << cosV;
        EXPECT_NEAR(hemisphere([&](const Vec3f& m) { return facets.pdf(v, m); }), 1.0, 1.5e-2)
            << int(dist) << " " << alpha << " " << cosV;
      }
    }
}

}  // namespace
}  // namespace farm
