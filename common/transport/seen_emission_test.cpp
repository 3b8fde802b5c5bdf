// SeenEmission against path tracing's own paths of its kind: the expectation of its sample at a
// uniform film point equals the sum of path tracing's values (same film point) over the paths
// L E it builds, which it finds only by hitting the light, so they carry its full weight; and
// against a furnace's walls, which every camera ray sees at their radiance.
#include "common/transport/seen_emission.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/math/statistics.h"
#include "common/render/local_render.h"
#include "common/render/render_job.h"
#include "common/sampling/sampler.h"
#include "common/scene/stiff_scenes.h"
#include "common/transport/path.h"
#include "common/transport/path_tracer.h"

namespace farm {
namespace {

const std::string kShared = FARM_SHARED_DIR;

struct Means {
  double emission, emissionSe, traced, tracedSe;
};

Means compare(const Scene& scene, int maxDepth, int n) {
  SeenEmission emission(scene);
  PathTracer tracer(scene, maxDepth);
  std::vector<double> a, b;
  a.reserve(size_t(n));
  b.reserve(size_t(n));
  Rng rngA(7, 1), rngB(7, 2);
  IndependentSampler sampler(&rngB);
  std::vector<Splat> splats;
  const float w = float(scene.camera().width()), h = float(scene.camera().height());
  for (int i = 0; i < n; ++i) {
    const Vec2f pa(rngA.nextFloat() * w, rngA.nextFloat() * h);
    splats.clear();
    emission.sample(pa, rngA, &splats);
    double value = 0;
    for (const Splat& s : splats) value += luminance(s.value);
    a.push_back(value);
    const Vec2f pb(rngB.nextFloat() * w, rngB.nextFloat() * h);
    double sum = 0;
    tracer.visitPaths(pb, sampler, [&](const PathTracer::TracedPath& t) {
      if (t.light) return;  // next-event estimation: x_1 is not specular
      Path x;
      x.vertices.assign(t.camera, t.camera + t.count);
      if (x.isSeenEmission(scene)) sum += luminance(t.value);
    });
    b.push_back(sum);
  }
  const MeanEstimate ea = meanOfIndependent(a), eb = meanOfIndependent(b);
  return {ea.mean, ea.standardError, eb.mean, eb.standardError};
}

TEST(SeenEmission, AgreesWithPathTracingsPathsOfItsKind) {
  RenderSettings settings;
  settings.width = settings.height = 64;
  auto scene = loadScene(kShared + "/scenes/cornell-box/scene.xml", settings);
  const Means m = compare(*scene, -1, 1 << 21);
  std::printf("cornell-box: seen emission %.6g +- %.3g, path tracing's %.6g +- %.3g\n", m.emission,
              m.emissionSe, m.traced, m.tracedSe);
  EXPECT_GT(m.emission, 0);
  EXPECT_LT(std::fabs(m.emission - m.traced), 4 * std::hypot(m.emissionSe, m.tracedSe));
}

// Inside a furnace whose walls emit Le every camera ray sees a wall: each pixel's L E is Le. The
// walls are large and near, so both strategies carry weight in every pixel.
TEST(SeenEmission, SeesTheFurnacesWallsAtTheirRadiance) {
  const Scene scene(stiff::furnaceBox(1, -1));
  SeenEmission emission(scene);
  std::vector<double> values;
  std::vector<Splat> splats;
  Rng rng(11, 3);
  const float w = float(scene.camera().width()), h = float(scene.camera().height());
  for (int i = 0; i < (1 << 18); ++i) {
    splats.clear();
    emission.sample(Vec2f(rng.nextFloat() * w, rng.nextFloat() * h), rng, &splats);
    double value = 0;
    for (const Splat& s : splats) value += luminance(s.value);
    values.push_back(value / scene.camera().pixelCount());
  }
  const MeanEstimate e = meanOfIndependent(values);
  const double expected = luminance(stiff::kFurnaceLe);
  std::printf("furnace walls: %.6f +- %.2g, expected %.6f\n", e.mean, e.standardError, expected);
  EXPECT_LT(std::fabs(e.mean - expected), 4 * e.standardError + 1e-4 * expected);
}

// mlt's chains splat their samples of the lights in view at seenEmissionScale, which the image's
// one scale Z / mutations must turn into the lights' radiance: the pixels whose filter lies on
// the light whole (all of their 5 x 5 neighbours at least half as bright as the light in a
// path-traced image, an independent choice) must read Le. Their values are independent
// estimates, and their spread gives the mean's standard error.
TEST(SeenEmission, MltImagesShowTheLightsInViewAtTheirRadiance) {
  RenderSettings settings;
  settings.width = settings.height = 256;
  auto scene = loadScene(kShared + "/scenes/cornell-box/scene.xml", settings);
  ASSERT_TRUE(SeenEmission::separates(*scene));
  const double le = luminance(scene->lights()[0].radiance);
  settings.algorithm = Algorithm::PathTracing;
  settings.samplesPerPixel = 4;
  const Image pt = renderLocally(RenderJob(scene, settings, "pt")).image;
  settings.algorithm = Algorithm::MLT;
  settings.mutationsPerPixel = 32;
  const Image mlt = renderLocally(RenderJob(scene, settings, "mlt")).image;
  std::vector<double> inside;
  for (int y = 2; y + 2 < pt.height; ++y) {
    for (int x = 2; x + 2 < pt.width; ++x) {
      bool whole = true;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) whole &= luminance(pt.at(x + dx, y + dy)) > 0.5 * le;
      if (whole) inside.push_back(luminance(mlt.at(x, y)));
    }
  }
  ASSERT_GE(inside.size(), 16u) << "the light covers too few pixels whole";
  const MeanEstimate e = meanOfIndependent(inside);
  std::printf("light's pixels in mlt's image: %.5g +- %.2g over %zu pixels, Le %.5g\n", e.mean,
              e.standardError, inside.size(), le);
  EXPECT_LT(std::fabs(e.mean - le), 4 * e.standardError);
  EXPECT_LT(e.standardError, 0.02 * le) << "too noisy to tell";
}

}  // namespace
}  // namespace farm
