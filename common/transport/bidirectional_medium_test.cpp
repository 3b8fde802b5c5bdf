// Bidirectional path tracing through participating media against the analytic answers of
// medium_transport_test: media of albedo 1 in a white furnace, single scattering in a slab,
// and a floor under an absorbing slab, seen by a camera (every strategy, light tracing from
// the sky included, connects through media).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/math/statistics.h"
#include "common/sampling/rng.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"
#include "common/transport/bidirectional.h"
#include "common/transport/medium_test_scenes.h"

namespace farm {
namespace {

// The film's mean radiance per channel: each sample's splats (its own film point's and those
// light tracing lands elsewhere) over the pixel count, independent from sample to sample.
std::vector<MeanEstimate> filmMean(const Scene& scene, int maxDepth, int samples, uint64_t seed) {
  BidirectionalTracer tracer(scene, maxDepth);
  Rng rng(seed, 13);
  IndependentSampler sampler(&rng);
  const Camera& camera = scene.camera();
  std::vector<double> values[3];
  std::vector<Splat> splats;
  for (int i = 0; i < samples; ++i) {
    splats.clear();
    const Vec2f film(rng.nextFloat() * float(camera.width()),
                     rng.nextFloat() * float(camera.height()));
    tracer.sample(film, sampler, &splats);
    Spectrum sum(0.0f);
    for (const Splat& s : splats) sum += s.value;
    for (int c = 0; c < 3; ++c) values[c].push_back(sum[c] / camera.pixelCount());
  }
  return {meanOfIndependent(values[0]), meanOfIndependent(values[1]), meanOfIndependent(values[2])};
}

// The mean over the film of L(direction of the pinhole's ray), on a fine grid of film points.
template <typename Radiance>
Spectrum filmAverage(const Scene& scene, const Radiance& L) {
  const Camera& camera = scene.camera();
  const int n = 24;
  Spectrum sum(0.0f);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Vec2f film((i + 0.5f) / n * float(camera.width()),
                       (j + 0.5f) / n * float(camera.height()));
      sum += L(camera.generateRay(film).d);
    }
  return sum / float(n * n);
}

void expectMean(const std::vector<MeanEstimate>& L, const Spectrum& expected,
                const std::string& what) {
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(L[c].mean, expected[c], 5 * L[c].standardError + 1e-6 * expected[c])
        << what << " channel " << c;
}

// A narrow camera at `eye` looking at `target`.
void aimCamera(SceneDescription* desc, const Vec3f& eye, const Vec3f& target) {
  desc->camera.toWorld = Matrix4::lookAt(eye, target, Vec3f(0, 1, 0));
  desc->camera.fovDegrees = 20;
  desc->camera.width = desc->camera.height = 8;
}

TEST(BidirectionalMedia, AlbedoOneMediaConserveTheSkysRadiance) {
  for (const MediumFurnace& furnace : mediumFurnaces()) {
    SceneDescription desc = furnace.scene;
    if (desc.camera.medium < 0) {
      aimCamera(&desc, Vec3f(0.1f, -0.2f, -4.0f), Vec3f(0.0f));
    } else {
      aimCamera(&desc, Vec3f(0.1f, 0.2f, -0.3f), Vec3f(0.4f, 0.1f, 1.0f));
    }
    const Scene scene(desc);
    expectMean(filmMean(scene, -1, 20000, 3), furnace.Le, furnace.name);
  }
}

// Light subpaths start in the medium around the light, which only the scene's geometry tells.
TEST(BidirectionalMedia, FilledFurnacesKeepTheirRadiance) {
  for (const MediumFurnace& furnace : filledFurnaces()) {
    const Scene scene(furnace.scene);
    expectMean(filmMean(scene, -1, 20000, 5), furnace.Le, furnace.name);
  }
}

TEST(BidirectionalMedia, SlabSingleScatteringMatchesItsClosedForm) {
  // Isotropic only: the closed form is quick enough to average over the film.
  for (float g : {0.0f}) {
    const SlabScene slab = singleScatteringSlab(g);
    SceneDescription desc = slab.scene;
    aimCamera(&desc, Vec3f(0.2f, 0.1f, 1.5f), Vec3f(0.8f, 0.1f, 0.0f));
    const Scene scene(desc);
    const Spectrum expected = filmAverage(scene, [&](const Vec3f& d) {
      Spectrum L;
      for (int c = 0; c < 3; ++c) L[c] = float(slab.radiance(c, -d.z));
      return L;
    });
    expectMean(filmMean(scene, 2, 100000, 7), expected, "g " + std::to_string(g));
  }
}

TEST(BidirectionalMedia, FloorUnderAnAbsorbingSlabMatchesE3) {
  for (bool dielectric : {false, true}) {
    const SlabScene slab = absorbingSlabOverFloor(dielectric);
    SceneDescription desc = slab.scene;
    aimCamera(&desc, Vec3f(0.3f, -0.2f, 3.0f), Vec3f(0.5f, 0.0f, 0.0f));
    const Scene scene(desc);
    const Spectrum expected = filmAverage(scene, [&](const Vec3f& d) {
      Spectrum L;
      for (int c = 0; c < 3; ++c) L[c] = float(slab.radiance(c, -d.z));
      return L;
    });
    expectMean(filmMean(scene, desc.maxDepth, 40000, 9), expected,
               dielectric ? "dielectric boundary" : "null boundary");
  }
}

}  // namespace
}  // namespace farm
