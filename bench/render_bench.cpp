// Rays per second and samples per second of each estimator on the shared scenes, single
// threaded (one chain), so that the figures compare the algorithms, not the scheduler.
//   build/bin/farm_bench --benchmark_filter=Cornell
#include <benchmark/benchmark.h>

#include <chrono>
#include <string>

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
