#pragma once
// The loop the throughput benchmarks share: one chain of a job run to `work` mutations (or
// samples, or seeds) per iteration, with the work and the rays it traced reported as rates; and
// the one run it repeats.
#include <benchmark/benchmark.h>

#include <cstdint>

#include "common/render/render_job.h"

namespace farm {

// Runs `spec` to `work` mutations (or samples, or seeds) in one flush, adding its work and the
// rays it traced to *done and *rays.
inline void runChainOnce(const RenderJob& job, ChainSpec spec, int64_t work, int64_t* done,
                         int64_t* rays) {
  spec.budget = work;
  spec.flushInterval = work;
  job.runChain(spec, [&](ChainFlush&& f) {
    *done += f.mutations;
    *rays += f.rays;
    return true;
  });
}

inline void runChainIterations(benchmark::State& state, const RenderJob& job, ChainSpec spec,
                               int64_t work, const char* workCounter) {
  int64_t done = 0, rays = 0;
  for (auto _ : state) runChainOnce(job, spec, work, &done, &rays);
  state.counters[workCounter] = benchmark::Counter(double(done), benchmark::Counter::kIsRate);
  state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
}

}  // namespace farm
