#include "common/render/local_render.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <mutex>

namespace farm {

LocalRenderResult renderLocally(const RenderJob& job) {
  auto start = std::chrono::steady_clock::now();
  LocalRenderResult result;
  result.bootstrap = job.bootstrap();
  std::vector<ChainSpec> specs = job.planChains(result.bootstrap);
  std::vector<double> sums(size_t(job.width()) * job.height() * 3, 0.0);
  uint32_t groups = 0;
  for (const ChainSpec& spec : specs) groups = std::max(groups, spec.errorGroup + 1);
  std::vector<std::vector<double>> groupSums(groups, std::vector<double>(sums.size(), 0.0));
  std::vector<int64_t> groupWork(groups, 0);
  result.chainTotals.assign(specs.size(), {0.0, 0.0, 0.0});
  result.chainWork.assign(specs.size(), 0);
  std::mutex mutex;
  const double budget = job.settings().timeBudgetSeconds;
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  auto timeUp = [&] { return budget > 0 && elapsed() >= budget; };
  // With a time budget the chains take turns, one flush each a round, as the coordinator
  // time-slices them (Job::answerLocked): run to the deadline instead, the first chain on each
  // thread would keep it until the time is up and the others would run one flush each after it,
  // so that the image would be a few chains' (and their stopping time, which depends on where
  // they went, would weigh their paths). Each turn resumes from the state its last flush left.
  std::vector<char> finished(specs.size(), 0);  // not vector<bool>: written from many threads
  auto allFinished = [&] {
    return std::all_of(finished.begin(), finished.end(), [](char f) { return f != 0; });
  };
  while (!allFinished() && !timeUp()) {
    tbb::parallel_for(size_t(0), specs.size(), [&](size_t i) {
      if (finished[i] || timeUp()) return;
      ChainSpec& spec = specs[i];
      job.runChain(spec, [&](ChainFlush&& f) {
        std::lock_guard<std::mutex> lock(mutex);
        std::array<double, 3>& total = result.chainTotals[i];
        std::vector<double>& groupSum = groupSums[spec.errorGroup];
        for (size_t k = 0; k < sums.size(); ++k) {
          sums[k] += f.splats[k];
          groupSum[k] += f.splats[k];
          total[k % 3] += f.splats[k];
        }
        groupWork[spec.errorGroup] += f.mutations;
        for (const MutationTally& t : f.tallies) {
          MutationTally& sum = result.tallies[t.name];
          sum.name = t.name;
          sum.proposed += t.proposed;
          sum.accepted += t.accepted;
        }
        result.largeSteps += f.largeSteps;
        result.work += f.mutations;
        result.chainWork[i] += f.mutations;
        result.rays += f.rays;
        result.rejected += f.rejected;
        spec.resumeState = std::move(f.state);
        spec.resumeMutations += f.mutations;
        spec.resumeFlushIndex = f.flushIndex + 1;
        if (f.finished) finished[i] = 1;
        return budget <= 0;  // with a budget: yield after one flush
      });
      if (budget <= 0) finished[i] = 1;
    });
  }
  result.image =
      job.resolve(sums, job.imageScale(result.bootstrap, result.work, result.largeSteps));
  // Every group's image with the same Z, pooled from all the chains: Z's error scales every
  // group alike (batch_means.h) and is counted once, not as spread between them.
  for (uint32_t g = 0; g < groups; ++g)
    result.groupImages.push_back(job.resolve(
        groupSums[g], job.imageScale(result.bootstrap, groupWork[g], result.largeSteps)));
  result.seconds = elapsed();
  return result;
}

}  // namespace farm
