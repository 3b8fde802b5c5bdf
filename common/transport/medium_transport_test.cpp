// Path tracing through participating media against answers that share nothing with its
// estimators: single scattering in a homogeneous slab under a constant sky (closed form, the
// exponential integral E2, and a quadrature of the phase function where it is not isotropic);
// media of albedo 1 in a white furnace (radiance equals the sky's, however many times light
// scatters, refracts or crosses a boundary); and single scattering in a density grid against a
// plain Monte Carlo integral over uniformly chosen points and directions with ray-marched
// transmittance.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "common/math/statistics.h"
#include "common/sampling/rng.h"
#include "common/sampling/warp.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"
#include "common/transport/medium_test_scenes.h"
#include "common/transport/path_tracer.h"

namespace farm {
namespace {

// Mean radiance along one ray over n independent path-tracing samples, per channel.
std::vector<MeanEstimate> meanRadiance(const Scene& scene, int maxDepth, const Ray& ray, int n,
                                       uint64_t seed) {
  PathTracer tracer(scene, maxDepth);
  Rng rng(seed, 9);
  IndependentSampler sampler(&rng);
  std::vector<double> values[3];
  for (int i = 0; i < n; ++i) {
    const Spectrum L = tracer.radiance(ray, sampler);
    for (int c = 0; c < 3; ++c) values[c].push_back(L[c]);
  }
  return {meanOfIndependent(values[0]), meanOfIndependent(values[1]), meanOfIndependent(values[2])};
}

TEST(MediumTransport, SlabSingleScatteringMatchesItsClosedForm) {
  for (float g : {0.0f, 0.6f}) {
    const SlabScene slab = singleScatteringSlab(g);
    const Scene scene(slab.scene);
    for (double mu0 : {1.0, 0.55}) {
      Ray ray;
      ray.d = Vec3f(float(std::sqrt(1 - mu0 * mu0)), 0, float(-mu0));
      ray.o = Vec3f(0.2f, 0.1f, 1.5f) - ray.d * 0.1f;
      const std::vector<MeanEstimate> L = meanRadiance(scene, 2, ray, 200000, 17);
      for (int c = 0; c < 3; ++c) {
        const double expected = slab.radiance(c, mu0);
        if (g == 0) {  // the quadrature agrees with the closed form it replaces
          const MediumDescription& m = slab.scene.media[0];
          const double st = double(m.sigmaA[c]) + m.sigmaS[c];
          EXPECT_NEAR(slabSingleScattering(slab.scene.environment.scale[c], st, m.sigmaS[c], 1, mu0,
                                           0, false),
                      expected, 2e-3 * expected);
        }
        EXPECT_NEAR(L[c].mean, expected, 5 * L[c].standardError)
            << "g " << g << " mu0 " << mu0 << " channel " << c;
      }
    }
  }
}

// A floor under an absorbing slab: connections and BSDF-sampled rays enter the slab from
// outside it, through a null boundary and through an index-matched dielectric.
TEST(MediumTransport, FloorUnderAnAbsorbingSlabMatchesE3) {
  for (bool dielectric : {false, true}) {
    const SlabScene slab = absorbingSlabOverFloor(dielectric);
    const Scene scene(slab.scene);
    Ray ray;
    ray.o = Vec3f(0.3f, -0.2f, 3.0f);
    ray.d = Vec3f(0, 0, -1);
    const std::vector<MeanEstimate> L = meanRadiance(scene, slab.scene.maxDepth, ray, 100000, 41);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(L[c].mean, slab.radiance(c, 1.0), 5 * L[c].standardError)
          << (dielectric ? "dielectric" : "null") << " boundary, channel " << c;
  }
}

TEST(MediumTransport, AlbedoOneMediaConserveTheSkysRadiance) {
  for (const MediumFurnace& furnace : mediumFurnaces()) {
    const Scene scene(furnace.scene);
    Ray ray;
    if (furnace.scene.camera.medium < 0) {
      ray.o = Vec3f(0.1f, -0.2f, -4.0f);
      ray.d = normalize(Vec3f(0.0f, 0.05f, 1.0f));
    } else {
      ray.o = Vec3f(0.1f, 0.2f, -0.3f);
      ray.d = normalize(Vec3f(0.3f, -0.1f, 1.0f));
    }
    const std::vector<MeanEstimate> L = meanRadiance(scene, -1, ray, 40000, 23);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(L[c].mean, furnace.Le[c], 5 * L[c].standardError + 1e-5)
          << furnace.name << " channel " << c;
  }
}

TEST(MediumTransport, FilledFurnacesKeepTheirRadiance) {
  for (const MediumFurnace& furnace : filledFurnaces()) {
    const Scene scene(furnace.scene);
    Ray ray;
    ray.o = furnace.scene.camera.toWorld.applyPoint(Vec3f(0.0f));
    ray.d = normalize(Vec3f(0.2f, 0.3f, 1.0f));
    const std::vector<MeanEstimate> L = meanRadiance(scene, -1, ray, 20000, 29);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(L[c].mean, furnace.Le[c], 5 * L[c].standardError)
          << furnace.name << " channel " << c;
  }
}

// Single scattering in a grid (the box [0, 1]^3, density zero outside it, the phase function
// isotropic) under a constant sky, against the integral it estimates taken by plain Monte
// Carlo: a uniform point along the ray, a uniform direction, transmittances by the midpoint
// rule at 1000 steps.
TEST(MediumTransport, GridSingleScatteringMatchesAnIndependentIntegral) {
  const Spectrum Le(1.0f, 0.7f, 1.2f);
  SceneDescription desc = underConstantSky(Le, 2);
  MediumDescription grid;
  grid.type = MediumDescription::Type::Grid;
  grid.sigmaA = Spectrum(1.0f, 0.5f, 2.0f);
  grid.sigmaS = Spectrum(2.0f, 2.5f, 1.0f);
  grid.nx = 4, grid.ny = 6, grid.nz = 5;
  Rng rng(8, 1);
  for (int i = 0; i < grid.nx * grid.ny * grid.nz; ++i) grid.density.push_back(2 * rng.nextFloat());
  desc.media.push_back(grid);
  desc.shapes.push_back(mediumBox(Vec3f(0.0f), Vec3f(1.0f), 0));
  const Scene scene(desc);
  const Medium& medium = scene.medium(0);

  Ray ray;
  ray.o = Vec3f(-0.5f, 0.3f, 0.4f);
  ray.d = normalize(Vec3f(1.0f, 0.25f, 0.1f));
  // Where the ray is inside the box: from x = 0 to its exit through x = 1 (y and z stay inside).
  const float t0 = 0.5f / ray.d.x, t1 = 1.5f / ray.d.x;
  const int steps = 1000;
  std::vector<double> independent[3];
  Rng r2(5, 5);
  for (int i = 0; i < 20000; ++i) {
    const float t = t0 + (t1 - t0) * r2.nextFloat();
    const Vec3f x = ray.o + ray.d * t;
    const Vec3f w = squareToUniformSphere({r2.nextFloat(), r2.nextFloat()});
    const double rho = medium.density(x);
    const Spectrum Tin = medium.marchedTransmittance(ray.o, ray.d, t, steps);
    const Spectrum Tout = medium.marchedTransmittance(x, w, 4.0f, steps);
    for (int c = 0; c < 3; ++c)
      independent[c].push_back(rho * grid.sigmaS[c] * Tin[c] * (1 / (4 * kPi)) * Le[c] * Tout[c] *
                               (t1 - t0) * 4 * kPi);
  }
  const Spectrum direct = medium.marchedTransmittance(ray.o, ray.d, 10.0f, 20000) * Le;
  const std::vector<MeanEstimate> L = meanRadiance(scene, 2, ray, 200000, 31);
  for (int c = 0; c < 3; ++c) {
    const MeanEstimate e = meanOfIndependent(independent[c]);
    const double expected = e.mean + direct[c];
    const double se =
        std::sqrt(e.standardError * e.standardError + L[c].standardError * L[c].standardError);
    EXPECT_NEAR(L[c].mean, expected, 5 * se) << "channel " << c;
  }
}

}  // namespace
}  // namespace farm
