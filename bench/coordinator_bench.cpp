// Flush encoding on the wire, and flushes per second a coordinator ingests, in memory and durable
// (--data: every flush in SQLite, synchronous, before it is acknowledged; the log folded into
// checkpoints), for a dense flush (path tracing: every pixel) and a sparse one (a Markov chain: 2%
// of the pixels), on a 256x256 film. One chain, one thread: the cost of one acceptance, not of the
// locks.
//   build/bin/farm_coordinator_bench
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <thread>

#include "common/render/render_job.h"
#include "coordinator/coordinator.h"
#include "proto/splat_codec.h"

namespace farm {
namespace {

void BM_AcceptFlush(benchmark::State& state, bool durable, double density) {
  const std::string dir = std::filesystem::temp_directory_path() /
                          ("farm-bench-" + std::to_string(::getpid()) + (durable ? "-d" : "-m"));
  std::filesystem::remove_all(dir);
  {
    CoordinatorOptions options;
    options.dataDir = dir;
    options.durable = durable;
    options.leaseSeconds = 3600;
    Coordinator coordinator(options);
    JobSpec spec;
    spec.scenePath = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";
    spec.settings.algorithm = Algorithm::PathTracing;
    spec.settings.width = 256;
    spec.settings.height = 256;
    spec.settings.samplesPerPixel = 1 << 20;
    spec.settings.numChains = 1;
    std::string job;
    if (!coordinator.submit(spec, &job).isOk()) {
      state.SkipWithError("cannot submit");
      return;
    }
    JobProgress p;
    do {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      coordinator.progress(job, 0, &p);
    } while (p.phase != JobPhase::kRendering && !isTerminal(p.phase));
    WorkerInfo info;
    info.capabilities = {Algorithm::PathTracing};
    std::string worker;
    coordinator.registerWorker(info, &worker);
    std::vector<WorkerLease> leases;
    coordinator.leaseChains(worker, 1, &leases);
    if (leases.size() != 1) {
      state.SkipWithError("no lease");
      return;
    }
    ChainFlush flush;
    flush.chainIndex = leases[0].lease.spec.chainIndex;
    flush.width = 256;
    flush.height = 256;
    flush.mutations = 4096;
    flush.splats.assign(size_t(256) * 256 * 3, 0.0f);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0, 1);
    for (size_t px = 0; px < size_t(256) * 256; ++px) {
      if (u(rng) >= density) continue;
      for (int c = 0; c < 3; ++c) flush.splats[3 * px + size_t(c)] = u(rng);
    }
    flush.state = std::string(64, 's');
    uint32_t index = 0;
    for (auto _ : state) {
      ChainFlush copy = flush;
      copy.flushIndex = index++;
      FlushAck ack;
      Status s = coordinator.acceptFlush(worker, job, leases[0].lease.epoch, std::move(copy), &ack);
      if (!s.isOk() || ack.result != FlushAck::Result::kAccepted) {
        state.SkipWithError(s.message().c_str());
        break;
      }
    }
    state.counters["flushes/s"] =
        benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["MiB/s"] = benchmark::Counter(
        double(state.iterations()) * double(flush.splats.size() * sizeof(float)) / (1 << 20),
        benchmark::Counter::kIsRate);
  }
  std::filesystem::remove_all(dir);
}

// What one flush of a real chain weighs on the wire (proto/splat_codec.h) against the dense
// float film it replaces, and how long encoding it takes: the Cornell box at 256x256, one flush
// of 4096 samples (pt) or mutations (mlt, pssmlt).
void BM_EncodeFlush(benchmark::State& state, Algorithm algorithm) {
  RenderSettings settings;
  settings.algorithm = algorithm;
  settings.width = 256;
  settings.height = 256;
  settings.samplesPerPixel = 1;
  settings.mutationsPerPixel = 1;
  settings.bootstrapSamples = 1 << 16;
  auto scene = loadScene(std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml", settings);
  RenderJob job(scene, settings, "bench");
  const BootstrapResult bootstrap = job.bootstrap();
  const std::vector<ChainSpec> chains = job.planChains(bootstrap);
  ChainSpec spec = chains.at(0);
  spec.flushInterval = 4096;
  ChainFlush first;
  job.runChain(spec, [&](ChainFlush&& flush) {
    first = std::move(flush);
    return false;
  });
  size_t bytes = 0;
  for (auto _ : state) {
    EncodedSplats e = encodeSplats(first.splats);
    bytes = e.bytes.size();
    benchmark::DoNotOptimize(e.bytes.data());
  }
  const double dense = double(first.splats.size() * sizeof(float));
  state.counters["dense KiB"] = dense / 1024;
  state.counters["sent KiB"] = double(bytes) / 1024;
  state.counters["ratio"] = double(bytes) / dense;
}

BENCHMARK_CAPTURE(BM_EncodeFlush, CornellPt, Algorithm::PathTracing)->MinTime(1.0);
BENCHMARK_CAPTURE(BM_EncodeFlush, CornellPssmlt, Algorithm::PSSMLT)->MinTime(1.0);
BENCHMARK_CAPTURE(BM_EncodeFlush, CornellMlt, Algorithm::MLT)->MinTime(1.0);

BENCHMARK_CAPTURE(BM_AcceptFlush, InMemoryDense, false, 1.0)->MinTime(2.0)->UseRealTime();
BENCHMARK_CAPTURE(BM_AcceptFlush, DurableDense, true, 1.0)->MinTime(2.0)->UseRealTime();
BENCHMARK_CAPTURE(BM_AcceptFlush, InMemorySparse, false, 0.02)->MinTime(2.0)->UseRealTime();
BENCHMARK_CAPTURE(BM_AcceptFlush, DurableSparse, true, 0.02)->MinTime(2.0)->UseRealTime();

}  // namespace
}  // namespace farm

BENCHMARK_MAIN();
