// The manifold perturbation's transition density against an answer computed without it: a pool
// (a flat water surface of index 1.33 over a diffuse floor) lit by a point light above the
// water and seen through the water, paths L S D S E that no sampler of BDPT's strategies can
// build (a point light is hit by no camera path, and a specular vertex joins nothing). From one
// such path x, E[f(y) / T(y | x)] over the perturbation's proposals is the integral, over the
// film annulus its offsets reach, of the luminance those paths carry to the camera: which the
// test integrates by quadrature with the optics written out in closed form (Snell's law, the
// Fresnel transmittance, the point light's irradiance through a flat interface from the
// derivative of its refraction map). Detailed balance and stationarity around curved glass are
// in mlt_chain_test.cpp.
#include "common/mcmc/mutations/manifold_perturbation.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "common/mcmc/mutations/manifold_walk.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"

namespace farm {
namespace {

constexpr double kEta = 1.33, kRho = 0.5, kIntensity = 10, kWater = 1;  // the surface at y = 1
const Vec3f kLight(0.2f, 2.5f, -0.1f);

SceneDescription pool() {
  SceneDescription d;
  d.camera.toWorld = Matrix4::lookAt(Vec3f(0.6f, 3, 0.4f), Vec3f(0, 0, 0), Vec3f(0, 0, 1));
  d.camera.fovDegrees = 40;
  d.camera.width = d.camera.height = 64;
  d.maxDepth = -1;
  BsdfDescription floor, water;
  floor.reflectance = Spectrum(float(kRho));
  water.type = BsdfDescription::Type::Dielectric;
  water.intIOR = float(kEta), water.extIOR = 1;
  d.bsdfs = {floor, water};
  d.shapes.push_back(quadShape(Vec3f(-10, 0, -10), Vec3f(0, 0, 20), Vec3f(20, 0, 0), 0));
  d.shapes.push_back(
      quadShape(Vec3f(-10, float(kWater), -10), Vec3f(0, 0, 20), Vec3f(20, 0, 0), 1));
  PointLightDescription light;
  light.position = kLight;
  light.intensity = Spectrum(float(kIntensity));
  d.pointLights.push_back(light);
  return d;
}

// --- The optics, in closed form ----------------------------------------------------------------

// Unpolarized Fresnel transmittance of the air-water interface for an angle of incidence in air.
double transmittance(double cosAir) {
  const double sinWater = std::sqrt(std::max(0.0, 1 - cosAir * cosAir)) / kEta;
  const double cosWater = std::sqrt(1 - sinWater * sinWater);
  const double rs = (cosAir - kEta * cosWater) / (cosAir + kEta * cosWater);
  const double rp = (kEta * cosAir - cosWater) / (kEta * cosAir + cosWater);
  return 1 - 0.5 * (rs * rs + rp * rp);
}

// Irradiance on the floor at horizontal distance r from below the light: a ray leaving the light
// at angle a from the vertical meets the floor at r(a) = h1 tan a + h2 tan b (sin a = eta sin b),
// so the solid angle per floor area is sin a / (r dr/da), times the intensity and the share the
// surface lets through.
double floorIrradiance(double r) {
  const double h1 = double(kLight.y) - kWater, h2 = kWater;
  auto reach = [&](double a) {
    const double b = std::asin(std::sin(a) / kEta);
    return h1 * std::tan(a) + h2 * std::tan(b);
  };
  double lo = 0, hi = 0.5 * M_PI - 1e-9;
  for (int i = 0; i < 200; ++i) (reach(0.5 * (lo + hi)) < r ? lo : hi) = 0.5 * (lo + hi);
  const double a = 0.5 * (lo + hi), b = std::asin(std::sin(a) / kEta);
  const double drda = h1 / (std::cos(a) * std::cos(a)) +
                      h2 / (std::cos(b) * std::cos(b)) * std::cos(a) / (kEta * std::cos(b));
  return kIntensity * transmittance(std::cos(a)) * std::sin(a) / (r * drda);
}

// The radiance the camera receives through film point `film` from the floor lit through the
// water: the floor's radiance rho / pi E, through the surface back into air (the Fresnel share,
// and radiance divided by eta^2 as the beam widens).
double filmRadiance(const Camera& camera, const Vec2f& film) {
  const Ray ray = camera.generateRay(film);
  const double ox = ray.o.x, oy = ray.o.y, oz = ray.o.z;
  double dx = ray.d.x, dy = ray.d.y, dz = ray.d.z;
  const double dl = std::sqrt(dx * dx + dy * dy + dz * dz);
  dx /= dl, dy /= dl, dz /= dl;
  const double t = (kWater - oy) / dy;
  const double sx = ox + t * dx, sz = oz + t * dz;
  const double cosAir = -dy, sinAir = std::sqrt(1 - cosAir * cosAir);
  const double sinWater = sinAir / kEta, cosWater = std::sqrt(1 - sinWater * sinWater);
  // Horizontally the ray keeps its heading; it descends kWater at cosWater.
  const double horizontal = std::sqrt(dx * dx + dz * dz);
  const double run = kWater * sinWater / cosWater;
  const double fx = sx + (horizontal > 0 ? dx / horizontal * run : 0);
  const double fz = sz + (horizontal > 0 ? dz / horizontal * run : 0);
  const double r = std::hypot(fx - kLight.x, fz - kLight.z);
  return transmittance(cosAir) / (kEta * kEta) * kRho / M_PI * floorIrradiance(r);
}

// --- The path and the test ---------------------------------------------------------------------

// x = L S D S E through the film's centre: the camera's side traced, the light's side placed on
// the manifold by a walk from a chain traced straight down.
Path poolPath(const MutationContext& context) {
  const Scene& scene = context.scene;
  const Camera& camera = scene.camera();
  PathVertex eye;
  eye.kind = PathVertex::Kind::Camera;
  eye.p = camera.position();
  PathVertex s2, d, s1, d0;
  EXPECT_TRUE(traceVertex(context, eye, camera.generateRay(Vec2f(32, 32)).d, &s2));
  Vec3f w;
  EXPECT_TRUE(specularBounce(scene, s2, eye.p, false, &w));
  EXPECT_TRUE(traceVertex(context, s2, w, &d));
  PathVertex light;
  light.kind = PathVertex::Kind::Light;
  light.p = kLight;
  light.light = 0;
  EXPECT_TRUE(traceVertex(context, light, Vec3f(0, -1, 0), &s1));
  EXPECT_TRUE(specularBounce(scene, s1, light.p, false, &w));
  EXPECT_TRUE(traceVertex(context, s1, w, &d0));
  Path chain, walked;
  chain.vertices = {light, s1, d0};
  EXPECT_TRUE(manifoldWalk(context, chain, 0, 2, d, &walked));
  Path x;
  x.vertices = {light, walked[1], d, s2, eye};
  return x;
}

TEST(ManifoldPerturbation, ProposalsIntegrateTheImageAroundThePath) {
  Scene scene(pool());
  MutationContext context{scene, -1};
  const Path x = poolPath(context);
  ASSERT_TRUE(x.contribution(scene, -1).carriesLight());
  ManifoldPerturbation mutation(context);
  ASSERT_TRUE(mutation.appliesTo(x));

  // The image's integral over the annulus of film offsets: a midpoint rule in the radius and
  // the angle about x's film point.
  const PerturbationSizes sizes = perturbationSizes(scene.camera());
  Vec2f centre;
  ASSERT_TRUE(scene.camera().project(x[4].p, normalize(x[3].p - x[4].p), &centre));
  const int nr = 600, nphi = 256;
  double exact = 0;
  for (int i = 0; i < nr; ++i) {
    const double r = sizes.r1 + (sizes.r2 - sizes.r1) * (i + 0.5) / nr;
    for (int j = 0; j < nphi; ++j) {
      const double phi = 2 * M_PI * (j + 0.5) / nphi;
      const Vec2f film(centre.x + float(r * std::cos(phi)), centre.y + float(r * std::sin(phi)));
      exact += filmRadiance(scene.camera(), film) * r;
    }
  }
  exact *= (sizes.r2 - sizes.r1) / nr * 2 * M_PI / nphi;

  // The proposals: f(y) / T(y | x), zero where none was made.
  const int tasks = 32, perTask = 4096;
  std::vector<double> sum(tasks, 0.0), sumSq(tasks, 0.0);
  std::vector<int> failed(tasks, 0);
  tbb::parallel_for(0, tasks, [&](int task) {
    MutationContext local{scene, -1};
    ManifoldPerturbation m(local);
    Rng rng(41, uint64_t(task));
    for (int i = 0; i < perTask; ++i) {
      Path y;
      MutationRecord record;
      double v = 0;
      if (m.propose(x, rng, &y, &record)) {
        const PathContribution fy = y.contribution(scene, -1);
        if (fy.carriesLight()) v = std::exp(fy.logLuminance - m.logDensity(x, y, record));
      } else {
        ++failed[task];
      }
      sum[task] += v;
      sumSq[task] += v * v;
    }
  });
  double s = 0, s2 = 0;
  int fails = 0;
  for (int t = 0; t < tasks; ++t) s += sum[t], s2 += sumSq[t], fails += failed[t];
  const double n = double(tasks) * perTask;
  const double mean = s / n, stdError = std::sqrt(std::max(0.0, s2 / n - mean * mean) / n);
  std::printf("E[f/T] %.6g +- %.2g, quadrature %.6g; %d of %.0f proposals failed\n", mean, stdError,
              exact, fails, n);
  EXPECT_NEAR(mean, exact, 4.4 * stdError);
  EXPECT_LT(stdError, 0.01 * exact);
  EXPECT_EQ(fails, 0) << "a flat interface has one chain for every floor point";
}

}  // namespace
}  // namespace farm
