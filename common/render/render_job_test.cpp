// The rays a chain reports (ChainFlush::rays: the progress page's and the benchmarks' rays per
// second) are the rays the scene traced for it, one for one, for every algorithm (a count dropped
// from BDPT's connections fails it); and the log replays them as the render traced them: Embree
// alone finds as many hits as the render's queries did (a check of the log and of the replay's
// set-up, which Embree's determinism makes exact). farm_bench's
// share of Embree's rate (bench/render_bench.cpp) stands on both.
#include "common/render/render_job.h"

#include <gtest/gtest.h>

#include <string>

#include "common/scene/scene.h"

namespace farm {
namespace {

const std::string kShared = FARM_SHARED_DIR;

TEST(RenderJob, EveryRayAChainCountsIsOneTheSceneTraced) {
  for (Algorithm algorithm :
       {Algorithm::PathTracing, Algorithm::Bidirectional, Algorithm::PSSMLT,
        Algorithm::PSSMLTOverPT, Algorithm::MMLT, Algorithm::MLT, Algorithm::ERPT}) {
    RenderSettings s;
    s.algorithm = algorithm;
    s.width = s.height = 32;
    s.bootstrapSamples = 1 << 12;
    s.numChains = 1;
    auto scene = loadScene(kShared + "/scenes/veach-bidir/scene.xml", s);
    RenderJob job(scene, s, "rays");
    ChainSpec spec = job.planChains(job.bootstrap())[0];
    spec.budget = algorithm == Algorithm::ERPT ? 256 : 2000;
    spec.flushInterval = spec.budget;
    RayLog log;
    int64_t counted = 0;
    scene->setRayLog(&log);
    job.runChain(spec, [&](ChainFlush&& f) {
      counted += f.rays;
      return true;
    });
    scene->setRayLog(nullptr);
    const std::string name = algorithmName(algorithm);
    EXPECT_GT(counted, 1000) << name;
    EXPECT_EQ(int64_t(log.rays.size()), counted) << name;
    // Replayed, the closest hits and the occlusion tests hit as often as they did in the render,
    // which was neither never nor always.
    int64_t hits = 0;
    for (const RayLog::Entry& e : log.rays) hits += e.hit;
    EXPECT_EQ(scene->traceLoggedRays(log), hits) << name;
    EXPECT_GT(hits, 0) << name;
    EXPECT_LT(hits, counted) << name;
  }
}

}  // namespace
}  // namespace farm
