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
#include "common/transport/path_tracer.h"

namespace farm {
namespace {

// An axis-aligned box as one mesh, its normals outwards, bounding medium `medium`.
ShapeDescription mediumBox(const Vec3f& lo, const Vec3f& hi, int medium) {
  const Vec3f e = hi - lo;
  const Vec3f x(e.x, 0, 0), y(0, e.y, 0), z(0, 0, e.z);
  const ShapeDescription faces[6] = {quadShape(lo, y, x, -1),                        // -z
                                     quadShape(Vec3f(lo.x, lo.y, hi.z), x, y, -1),   // +z
                                     quadShape(lo, x, z, -1),                        // -y
                                     quadShape(Vec3f(lo.x, hi.y, lo.z), z, x, -1),   // +y
                                     quadShape(lo, z, y, -1),                        // -x
                                     quadShape(Vec3f(hi.x, lo.y, lo.z), y, z, -1)};  // +x
  ShapeDescription box;
  for (const ShapeDescription& f : faces) {
    const uint32_t base = uint32_t(box.positions.size());
    box.positions.insert(box.positions.end(), f.positions.begin(), f.positions.end());
    for (uint32_t i : f.indices) box.indices.push_back(base + i);
  }
  box.hasMediumInterface = true;
  box.interiorMedium = medium;
  box.nullBoundary = true;
  box.origin = "medium box";
  return box;
}

SceneDescription underConstantSky(const Spectrum& Le, int maxDepth) {
  SceneDescription d;
  d.maxDepth = maxDepth;
  d.environment.present = true;
  d.environment.scale = Le;
  return d;
}

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

double exponentialIntegral2(double x) {
  if (x < 1e-12) return 1;
  return std::exp(-x) + x * std::expint(-x);  // E2 = e^-x - x E1, E1(x) = -Ei(-x)
}

// Single scattering of a constant sky Le in the slab 0 <= z <= depth (sigma_t, sigma_s of one
// channel, phase function `phase`), seen along a ray entering its top at cosine mu0 below the
// horizontal: what reaches the eye unscattered plus what the slab scatters once towards it,
//   Le [exp(-st D / mu0) + ss int_0^{D/mu0} exp(-st t) int_S2 p(w) exp(-st l(z, w)) dw dt]
// where l is the way out of the slab from depth z in direction w. Isotropic: the inner integral
// is (E2(st z) + E2(st (D - z))) / 2; otherwise a quadrature over the sphere.
double slabSingleScattering(double Le, double st, double ss, double D, double mu0, float g,
                            bool closedForm) {
  const HenyeyGreenstein phase(g);
  const Vec3f travel(float(std::sqrt(1 - mu0 * mu0)), 0, float(-mu0));  // downwards
  const int nt = closedForm ? 4000 : 200, nmu = 200, nphi = 48;
  const double length = D / mu0, dt = length / nt;
  double scattered = 0;
  for (int i = 0; i < nt; ++i) {
    const double t = (i + 0.5) * dt, z = t * mu0;  // z: depth below the top
    double inner;
    if (closedForm) {
      inner = 0.5 * (exponentialIntegral2(st * z) + exponentialIntegral2(st * (D - z)));
    } else {
      inner = 0;
      for (int a = 0; a < 2 * nmu; ++a) {
        const double mu = -1 + (a + 0.5) / nmu;  // the direction's z
        const double way = mu > 0 ? z / mu : (D - z) / -mu;
        const double s = std::sqrt(1 - mu * mu);
        for (int b = 0; b < nphi; ++b) {
          const double phi = (b + 0.5) * 2 * kPi / nphi;
          const Vec3f w(float(s * std::cos(phi)), float(s * std::sin(phi)), float(mu));
          inner += phase.eval(-travel, w) * std::exp(-st * way) * (1.0 / nmu) * (2 * kPi / nphi);
        }
      }
    }
    scattered += std::exp(-st * t) * inner * dt;
  }
  return Le * (std::exp(-st * length) + ss * scattered);
}

TEST(MediumTransport, SlabSingleScatteringMatchesItsClosedForm) {
  const Spectrum Le(1.0f, 0.8f, 1.3f);
  const float D = 1;
  for (float g : {0.0f, 0.6f}) {
    SceneDescription desc = underConstantSky(Le, 2);  // camera - scattering - sky
    MediumDescription m;
    m.sigmaA = Spectrum(0.3f, 0.1f, 0.0f);
    m.sigmaS = Spectrum(0.5f, 1.0f, 2.0f);
    m.g = g;
    desc.media.push_back(m);
    // A slab 2000 times wider than thick: the infinite slab to within exp(-1000).
    desc.shapes.push_back(mediumBox(Vec3f(-1000, -1000, 0), Vec3f(1000, 1000, D), 0));
    const Scene scene(desc);
    for (double mu0 : {1.0, 0.55}) {
      Ray ray;
      ray.d = Vec3f(float(std::sqrt(1 - mu0 * mu0)), 0, float(-mu0));
      ray.o = Vec3f(0.2f, 0.1f, D + 0.5f) - ray.d * 0.1f;
      const std::vector<MeanEstimate> L = meanRadiance(scene, 2, ray, 200000, 17);
      for (int c = 0; c < 3; ++c) {
        const double st = double(m.sigmaA[c]) + m.sigmaS[c];
        const double expected = slabSingleScattering(Le[c], st, m.sigmaS[c], D, mu0, g, g == 0);
        if (g == 0) {  // the quadrature agrees with the closed form it replaces
          EXPECT_NEAR(slabSingleScattering(Le[c], st, m.sigmaS[c], D, mu0, 0, false), expected,
                      2e-3 * expected);
        }
        EXPECT_NEAR(L[c].mean, expected, 5 * L[c].standardError)
            << "g " << g << " mu0 " << mu0 << " channel " << c;
      }
    }
  }
}

// A diffuse floor (albedo rho) under a purely absorbing slab of optical thickness tau, lit by a
// constant sky and seen through the slab from straight above, light reflected once: next-event
// rays and BSDF-sampled ones enter the slab from outside it. The floor's radiance is
// rho Le int 2 mu exp(-tau / mu) dmu = 2 rho Le E3(tau); the eye sees it times exp(-tau).
// The slab bounded by a null boundary, or by an index-matched dielectric (Fresnel 0: every ray
// is refracted straight on, so the answer is the same, but rays cross it by sampling its BSDF
// and no next-event ray passes it: 6 edges from the eye to the sky).
void expectFloorUnderAbsorbingSlab(bool dielectricBoundary) {
  const Spectrum Le(1.0f, 0.6f, 1.4f);
  const int maxDepth = dielectricBoundary ? 6 : 2;
  SceneDescription desc = underConstantSky(Le, maxDepth);
  MediumDescription m;
  m.sigmaA = Spectrum(0.2f, 0.7f, 1.5f);
  desc.media.push_back(m);
  const float D = 1;
  BsdfDescription floor;
  floor.reflectance = Spectrum(0.8f, 0.5f, 0.3f);
  desc.bsdfs.push_back(floor);
  desc.shapes.push_back(mediumBox(Vec3f(-1000, -1000, 0.5f), Vec3f(1000, 1000, 0.5f + D), 0));
  if (dielectricBoundary) {
    BsdfDescription matched;
    matched.type = BsdfDescription::Type::Dielectric;
    matched.intIOR = matched.extIOR = 1.0f;
    desc.bsdfs.push_back(matched);
    desc.shapes.back().nullBoundary = false;
    desc.shapes.back().bsdf = 1;
  }
  desc.shapes.push_back(quadShape(Vec3f(-1000, -1000, 0), Vec3f(2000, 0, 0), Vec3f(0, 2000, 0), 0));
  const Scene scene(desc);
  Ray ray;
  ray.o = Vec3f(0.3f, -0.2f, 3.0f);
  ray.d = Vec3f(0, 0, -1);
  const std::vector<MeanEstimate> L = meanRadiance(scene, maxDepth, ray, 100000, 41);
  for (int c = 0; c < 3; ++c) {
    const double tau = double(m.sigmaA[c]) * D;
    const double e3 = 0.5 * (std::exp(-tau) - tau * exponentialIntegral2(tau));
    const double expected = std::exp(-tau) * 2 * floor.reflectance[c] * Le[c] * e3;
    EXPECT_NEAR(L[c].mean, expected, 5 * L[c].standardError)
        << (dielectricBoundary ? "dielectric" : "null") << " boundary, channel " << c;
  }
}

TEST(MediumTransport, FloorUnderAnAbsorbingSlabMatchesE3) {
  expectFloorUnderAbsorbingSlab(false);
  expectFloorUnderAbsorbingSlab(true);
}

// A sphere of medium of albedo 1 under a constant sky: nothing is lost, so every ray sees the
// sky's radiance, through any number of scatterings and whatever bounds the medium.
void expectFurnace(SceneDescription desc, const Ray& ray, const Spectrum& Le,
                   const std::string& what) {
  const Scene scene(desc);
  const std::vector<MeanEstimate> L = meanRadiance(scene, -1, ray, 40000, 23);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(L[c].mean, Le[c], 5 * L[c].standardError + 1e-5) << what << " channel " << c;
}

TEST(MediumTransport, AlbedoOneMediaConserveTheSkysRadiance) {
  const Spectrum Le(1.0f, 0.5f, 2.0f);
  MediumDescription m;
  m.sigmaS = Spectrum(1.5f, 3.0f, 0.7f);  // optically thick in green: many scatterings
  m.g = 0.5f;
  Ray outside;
  outside.o = Vec3f(0.1f, -0.2f, -4.0f);
  outside.d = normalize(Vec3f(0.0f, 0.05f, 1.0f));

  // Bounded by a null boundary.
  SceneDescription desc = underConstantSky(Le, -1);
  desc.media.push_back(m);
  ShapeDescription ball = sphereShape(Vec3f(0.0f), 1.0f, -1);
  ball.hasMediumInterface = true;
  ball.interiorMedium = 0;
  ball.nullBoundary = true;
  desc.shapes.push_back(ball);
  expectFurnace(desc, outside, Le, "null boundary");

  // Seen from inside: the camera sits in the medium.
  desc.camera.medium = 0;
  Ray inside;
  inside.o = Vec3f(0.1f, 0.2f, -0.3f);
  inside.d = normalize(Vec3f(0.3f, -0.1f, 1.0f));
  expectFurnace(desc, inside, Le, "camera in the medium");
  desc.camera.medium = -1;

  // Bounded by glass, which reflects and refracts without loss.
  BsdfDescription glass;
  glass.type = BsdfDescription::Type::Dielectric;
  glass.intIOR = 1.33f;
  glass.extIOR = 1.0f;
  desc.bsdfs.push_back(glass);
  desc.shapes[0].nullBoundary = false;
  desc.shapes[0].bsdf = 0;
  expectFurnace(desc, outside, Le, "glass boundary");

  // A density grid (sigma_t grey, the grid's zeros and ramps inside the ball's box).
  MediumDescription grid;
  grid.type = MediumDescription::Type::Grid;
  grid.sigmaS = Spectrum(4.0f);
  grid.nx = grid.ny = grid.nz = 5;
  Rng rng(2, 2);
  for (int i = 0; i < 125; ++i)
    grid.density.push_back(rng.nextFloat() < 0.2f ? 0 : rng.nextFloat());
  grid.worldToGrid = Matrix4::scale(Vec3f(0.5f)) * Matrix4::translate(Vec3f(1.0f));
  grid.g = -0.3f;
  desc.media[0] = grid;
  desc.shapes[0].nullBoundary = true;
  desc.shapes[0].bsdf = -1;
  expectFurnace(desc, outside, Le, "density grid");
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
