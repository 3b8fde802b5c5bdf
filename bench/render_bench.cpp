// Rays per second and samples per second of each estimator on the shared scenes, single
// threaded (one chain), so that the figures compare the algorithms, not the scheduler.
//   build/bin/farm_bench --benchmark_filter=Cornell
//
// BM_Share sets each algorithm beside the hardware (issue 45): on every shared scene, the rays an
// algorithm traces (logged: Scene::setRayLog) are traced again by Embree alone, in their order
// and with nothing worked out of the hits (Scene::traceLoggedRays), which is the rate the core
// allows for that algorithm's own mix of closest hits and occlusion tests, their directions and
// lengths. It reports the algorithm's rays/s, that rate ("embree rays/s"), the share of it the
// algorithm reaches, its work (samples, mutations or seeds) per second and the bytes it allocates
// per unit of work (through operator new, counted here), beyond what each run of a work unit
// allocates whatever its length (its flush's film).
//   build/bin/farm_bench --benchmark_filter=Share
#include <benchmark/benchmark.h>

#include <chrono>
#include <string>

#include "bench/allocation_count.h"
#include "bench/chain_bench.h"
#include "common/mcmc/bootstrap.h"
#include "common/render/render_job.h"
#include "common/scene/scene.h"
#include "common/transport/bidirectional.h"
#include "common/transport/path_tracer.h"

namespace farm {
namespace {

std::shared_ptr<Scene> sharedScene(const std::string& name) {
  RenderSettings s;
  s.width = 256;
  s.height = name == "veach-mis" ? 144 : 256;
  return loadScene(std::string(FARM_SHARED_DIR) + "/scenes/" + name + "/scene.xml", s);
}

template <typename Tracer>
void tracerThroughput(benchmark::State& state, const std::string& name) {
  auto scene = sharedScene(name);
  Tracer tracer(*scene, scene->maxDepth());
  Rng rng(1, 1);
  IndependentSampler sampler(&rng);
  std::vector<Splat> splats;
  const Camera& cam = scene->camera();
  int64_t samples = 0;
  for (auto _ : state) {
    splats.clear();
    Vec2f film(rng.nextFloat() * cam.width(), rng.nextFloat() * cam.height());
    tracer.sample(film, sampler, &splats);
    ++samples;
  }
  state.counters["rays/s"] = benchmark::Counter(double(tracer.rays()), benchmark::Counter::kIsRate);
  state.counters["samples/s"] = benchmark::Counter(double(samples), benchmark::Counter::kIsRate);
}

void BM_PathTracing(benchmark::State& state, const char* scene) {
  tracerThroughput<PathTracer>(state, scene);
}
void BM_Bidirectional(benchmark::State& state, const char* scene) {
  tracerThroughput<BidirectionalTracer>(state, scene);
}

// Mutations (or, for ERPT, seeds) per second of one chain of the given algorithm, bootstrap
// excluded.
void BM_Chain(benchmark::State& state, const char* name, Algorithm algorithm) {
  RenderSettings s;
  s.algorithm = algorithm;
  s.width = 256;
  s.height = 256;
  s.bootstrapSamples = 1 << 15;
  s.numChains = 1;
  auto scene = loadScene(std::string(FARM_SHARED_DIR) + "/scenes/" + name + "/scene.xml", s);
  RenderJob job(scene, s, "bench");
  const bool erpt = algorithm == Algorithm::ERPT;
  runChainIterations(state, job, job.planChains(job.bootstrap())[0], erpt ? 1024 : 20000,
                     erpt ? "seeds/s" : "mutations/s");
}

// One work unit of `algorithm` on a shared scene at 256 pixels wide, run again and again to
// `work` samples, mutations or seeds (the bootstrap excluded), against Embree's rate on the rays
// the same work traces.
void BM_Share(benchmark::State& state, const char* name, const char* file, Algorithm algorithm) {
  RenderSettings s;
  s.algorithm = algorithm;
  s.width = 256;
  s.bootstrapSamples = 1 << 15;
  s.numChains = 1;
  auto scene = loadScene(std::string(FARM_SHARED_DIR) + "/scenes/" + name + "/" + file, s);
  RenderJob job(scene, s, "bench");
  const ChainSpec first = job.planChains(job.bootstrap())[0];
  const bool samples = algorithm == Algorithm::PathTracing || algorithm == Algorithm::Bidirectional;
  const int64_t work = samples ? 16384 : algorithm == Algorithm::ERPT ? 256 : 20000;
  int64_t done = 0, rays = 0;
  auto run = [&](int64_t budget) { runChainOnce(job, first, budget, &done, &rays); };
  // Embree's rate on this work's rays, over at least half a second of replays.
  RayLog log;
  scene->setRayLog(&log);
  run(work);
  scene->setRayLog(nullptr);
  using Clock = std::chrono::steady_clock;
  int64_t replayed = 0, hits = 0;
  const auto replayStart = Clock::now();
  double replaySeconds = 0;
  while (replaySeconds < 0.5) {
    hits += scene->traceLoggedRays(log);
    replayed += int64_t(log.rays.size());
    replaySeconds = std::chrono::duration<double>(Clock::now() - replayStart).count();
  }
  benchmark::DoNotOptimize(hits);
  const double embreeRate = double(replayed) / replaySeconds;

  // What a run allocates whatever its work (its flush's film above all, 36 bytes a pixel): a run
  // of one unit of work, left out of the bytes per unit.
  int64_t allocatedBefore = allocatedBytes();
  run(1);
  const double perRun = double(allocatedBytes() - allocatedBefore);

  done = rays = 0;
  int64_t runs = 0;
  allocatedBefore = allocatedBytes();
  const auto start = Clock::now();
  for (auto _ : state) {
    run(work);
    ++runs;
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  const double bytes = double(allocatedBytes() - allocatedBefore) - perRun * double(runs);
  state.counters["rays/s"] = double(rays) / seconds;
  state.counters["embree rays/s"] = embreeRate;
  state.counters["share"] = double(rays) / seconds / embreeRate;
  state.counters["work/s"] = double(done) / seconds;
  state.counters["bytes/work"] = done > 0 ? bytes / double(done) : 0.0;
}

// BM_Share/<scene><algorithm> for every shared scene and algorithm.
const bool kShareRegistered = [] {
  struct SharedScene {
    const char *name, *label, *file;
  };
  struct Kind {
    Algorithm algorithm;
    const char* label;
  };
  for (const SharedScene& scene : {SharedScene{"cornell-box", "Cornell", "scene.xml"},
                                   SharedScene{"cornell-box-pbrt", "CornellPbrt", "scene.pbrt"},
                                   SharedScene{"veach-ajar", "VeachAjar", "scene.pbrt"},
                                   SharedScene{"veach-bidir", "VeachBidir", "scene.xml"},
                                   SharedScene{"veach-mis", "VeachMis", "scene.xml"},
                                   SharedScene{"water-caustic", "WaterCaustic", "scene.xml"}})
    for (const Kind& kind :
         {Kind{Algorithm::PathTracing, "Pt"}, Kind{Algorithm::Bidirectional, "Bdpt"},
          Kind{Algorithm::PSSMLT, "Pssmlt"}, Kind{Algorithm::MMLT, "Mmlt"},
          Kind{Algorithm::MLT, "Mlt"}, Kind{Algorithm::ERPT, "Erpt"}})
      benchmark::RegisterBenchmark((std::string("BM_Share/") + scene.label + kind.label).c_str(),
                                   BM_Share, scene.name, scene.file, kind.algorithm)
          ->MinTime(1.0)
          ->Unit(benchmark::kMillisecond);
  return true;
}();

BENCHMARK_CAPTURE(BM_PathTracing, Cornell, "cornell-box")->MinTime(2.0);
BENCHMARK_CAPTURE(BM_Bidirectional, Cornell, "cornell-box")->MinTime(2.0);
BENCHMARK_CAPTURE(BM_Chain, CornellPssmlt, "cornell-box", Algorithm::PSSMLT)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Chain, CornellPssmltOverPt, "cornell-box", Algorithm::PSSMLTOverPT)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Chain, CornellMmlt, "cornell-box", Algorithm::MMLT)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Chain, CornellMlt, "cornell-box", Algorithm::MLT)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Chain, CornellErpt, "cornell-box", Algorithm::ERPT)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PathTracing, WaterCaustic, "water-caustic")->MinTime(2.0);
BENCHMARK_CAPTURE(BM_Bidirectional, WaterCaustic, "water-caustic")->MinTime(2.0);
BENCHMARK_CAPTURE(BM_Chain, WaterCausticPssmlt, "water-caustic", Algorithm::PSSMLT)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Chain, WaterCausticMlt, "water-caustic", Algorithm::MLT)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Chain, WaterCausticErpt, "water-caustic", Algorithm::ERPT)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace farm

BENCHMARK_MAIN();
