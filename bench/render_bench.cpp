// Rays per second and samples per second of each estimator on the shared scenes, single
// threaded (one chain), so that the figures compare the algorithms, not the scheduler.
//   build/bin/farm_bench --benchmark_filter=Cornell
#include <benchmark/benchmark.h>

#include <chrono>
#include <string>

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

// Mutations per second of one PSSMLT chain (bootstrap excluded).
void BM_Pssmlt(benchmark::State& state, const char* name) {
  RenderSettings s;
  s.algorithm = Algorithm::PSSMLT;
  s.width = 256;
  s.height = 256;
  s.bootstrapSamples = 1 << 15;
  s.numChains = 1;
  auto scene = loadScene(std::string(FARM_SHARED_DIR) + "/scenes/" + name + "/scene.xml", s);
  RenderJob job(scene, s, "bench");
  ChainSpec spec = job.planChains(job.bootstrap())[0];
  int64_t mutations = 0;
  for (auto _ : state) {
    spec.budget = 20000;
    spec.flushInterval = 20000;
    job.runChain(spec, [&](ChainFlush&& f) {
      mutations += f.mutations;
      return true;
    });
  }
  state.counters["mutations/s"] =
      benchmark::Counter(double(mutations), benchmark::Counter::kIsRate);
}

BENCHMARK_CAPTURE(BM_PathTracing, Cornell, "cornell-box")->MinTime(2.0);
BENCHMARK_CAPTURE(BM_Bidirectional, Cornell, "cornell-box")->MinTime(2.0);
BENCHMARK_CAPTURE(BM_Pssmlt, Cornell, "cornell-box")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PathTracing, WaterCaustic, "water-caustic")->MinTime(2.0);
BENCHMARK_CAPTURE(BM_Bidirectional, WaterCaustic, "water-caustic")->MinTime(2.0);
BENCHMARK_CAPTURE(BM_Pssmlt, WaterCaustic, "water-caustic")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace farm

BENCHMARK_MAIN();
