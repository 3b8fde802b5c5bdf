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
#include "common/scene/pool_scene.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"

namespace farm {
namespace {

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
  light.p = pool::kLight;
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
  Scene scene(pool::scene());
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
      exact += pool::filmRadiance(scene.camera(), film) * r;
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
