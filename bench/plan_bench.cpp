// What each part the plan leaves out costs when it is in (common/plan/render_plan.h): the
// Cornell box as its file has it (every part left out) against the same box with one part in
// but inert, so that the image stays the same and only the code path differs:
//   lens:        a thin lens of radius 1e-6 (the camera samples a lens point for every ray)
//   textures:    each diffuse reflectance given by a constant texture of the same value
//   environment: a constant environment of radiance 1e-6 (escaped rays look it up, and light
//                selection and BDPT's light subpaths include it)
//   media:       the camera in a homogeneous medium of extinction 1e-6 (medium tracking, free
//                flights and transmittance on every segment); a medium without a boundary
//                fills all space, so a ray that leaves the room scatters about 1e6 away and the
//                path goes on there, as the scene asks
//   bounded:     the same medium inside a box of null boundaries around the room and the
//                camera: what tracking costs once rays that leave the room leave the medium
// for path tracing and BDPT; and mlt's mutation mix with the multi-chain and manifold
// perturbations at zero weight (the plan) against their default weights (--no-plan). One chain,
// one thread; the ratio of samples (or mutations) per second between a pair is the saving.
//   build/bin/farm_plan_bench
#include <benchmark/benchmark.h>

#include <algorithm>
#include <string>

#include "bench/chain_bench.h"
#include "common/plan/render_plan.h"
#include "common/render/render_job.h"
#include "common/scene/film_override.h"
#include "common/scene/loaders/scene_loader.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"

namespace farm {
namespace {

enum class Part { None, Lens, Textures, Environment, Media, BoundedMedia };

// Six faces of null boundary around everything in d and its camera, 1% of the diagonal out,
// their normals outwards (the interior, medium 0, opposite the normal).
void boundMediumZero(SceneDescription& d) {
  Vec3f lo(d.camera.toWorld.applyPoint(Vec3f(0.0f))), hi = lo;
  for (const ShapeDescription& shape : d.shapes) {
    for (const Vec3f& p : shape.positions) {
      lo = Vec3f(std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z));
      hi = Vec3f(std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z));
    }
  }
  const Vec3f pad((hi - lo) * 0.01f);
  lo = lo - pad;
  hi = hi + pad;
  const Vec3f e = hi - lo, x(e.x, 0, 0), y(0, e.y, 0), z(0, 0, e.z);
  for (ShapeDescription f :
       {quadShape(lo, y, x, -1), quadShape(Vec3f(lo.x, lo.y, hi.z), x, y, -1),
        quadShape(lo, x, z, -1), quadShape(Vec3f(lo.x, hi.y, lo.z), z, x, -1),
        quadShape(lo, z, y, -1), quadShape(Vec3f(hi.x, lo.y, lo.z), y, z, -1)}) {
    f.hasMediumInterface = true;
    f.interiorMedium = 0;
    f.nullBoundary = true;
    d.shapes.push_back(f);
  }
}

std::shared_ptr<Scene> cornell(Part part) {
  SceneDescription d =
      loadSceneDescription(std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml");
  applyFilmOverride(d, 256, 256);
  switch (part) {
    case Part::None:
      break;
    case Part::Lens:
      d.camera.lensRadius = 1e-6f;
      break;
    case Part::Textures:
      for (BsdfDescription& b : d.bsdfs) {
        if (b.type != BsdfDescription::Type::Diffuse || b.reflectanceTexture >= 0) continue;
        TextureDescription t;
        t.type = TextureDescription::Type::Constant;
        t.value = b.reflectance;
        b.reflectanceTexture = int(d.textures.size());
        d.textures.push_back(t);
      }
      break;
    case Part::Environment:
      d.environment.present = true;
      d.environment.scale = Spectrum(1e-6f);
      break;
    case Part::Media:
    case Part::BoundedMedia: {
      MediumDescription m;
      m.sigmaS = Spectrum(1e-6f);
      d.media.push_back(m);
      d.camera.medium = 0;
      if (part == Part::BoundedMedia) boundMediumZero(d);
      break;
    }
  }
  return std::make_shared<Scene>(d);
}

void runOneChain(benchmark::State& state, std::shared_ptr<Scene> scene, RenderSettings s) {
  s.width = s.height = 256;
  s.bootstrapSamples = 1 << 15;
  s.numChains = 1;
  RenderJob job(scene, s, "bench");
  runChainIterations(state, job, job.planChains(job.bootstrap())[0], 20000, "work/s");
}

void BM_Part(benchmark::State& state, Algorithm algorithm, Part part) {
  RenderSettings s;
  s.algorithm = algorithm;
  runOneChain(state, cornell(part), s);
}

// mlt with the plan's mix (the specular mutations at zero weight) or the default one.
void BM_MltMix(benchmark::State& state, bool planned) {
  std::shared_ptr<Scene> scene = cornell(Part::None);
  RenderSettings s;
  s.algorithm = Algorithm::MLT;
  s.mutationMix = planned ? plannedMutationMix(analyseScene(*scene), MutationMix()) : MutationMix();
  runOneChain(state, scene, s);
}

#define FARM_PARTS(name, algorithm)                                                                \
  BENCHMARK_CAPTURE(BM_Part, name##LeftOut, algorithm, Part::None)->Unit(benchmark::kMillisecond); \
  BENCHMARK_CAPTURE(BM_Part, name##Lens, algorithm, Part::Lens)->Unit(benchmark::kMillisecond);    \
  BENCHMARK_CAPTURE(BM_Part, name##Textures, algorithm, Part::Textures)                            \
      ->Unit(benchmark::kMillisecond);                                                             \
  BENCHMARK_CAPTURE(BM_Part, name##Environment, algorithm, Part::Environment)                      \
      ->Unit(benchmark::kMillisecond);                                                             \
  BENCHMARK_CAPTURE(BM_Part, name##Media, algorithm, Part::Media)->Unit(benchmark::kMillisecond);  \
  BENCHMARK_CAPTURE(BM_Part, name##BoundedMedia, algorithm, Part::BoundedMedia)                    \
      ->Unit(benchmark::kMillisecond)

FARM_PARTS(CornellPt, Algorithm::PathTracing);
FARM_PARTS(CornellBdpt, Algorithm::Bidirectional);
BENCHMARK_CAPTURE(BM_MltMix, CornellMltPlanned, true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MltMix, CornellMltEveryMutation, false)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace farm

BENCHMARK_MAIN();
