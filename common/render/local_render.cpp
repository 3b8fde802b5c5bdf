#include "common/render/local_render.h"

#include <tbb/parallel_for.h>

#include <chrono>
#include <mutex>

namespace farm {

LocalRenderResult renderLocally(const RenderJob& job) {
  auto start = std::chrono::steady_clock::now();
  LocalRenderResult result;
  result.bootstrap = job.bootstrap();
  std::vector<ChainSpec> specs = job.planChains(result.bootstrap);
  std::vector<double> sums(size_t(job.width()) * job.height() * 3, 0.0);
  result.chainTotals.assign(specs.size(), {0.0, 0.0, 0.0});
  std::mutex mutex;
  const double budget = job.settings().timeBudgetSeconds;
  tbb::parallel_for(size_t(0), specs.size(), [&](size_t i) {
    job.runChain(specs[i], [&](ChainFlush&& f) {
      std::lock_guard<std::mutex> lock(mutex);
      std::array<double, 3>& total = result.chainTotals[i];
      for (size_t k = 0; k < sums.size(); ++k) {
        sums[k] += f.splats[k];
        total[k % 3] += f.splats[k];
      }
      for (const MutationTally& t : f.tallies) {
        MutationTally& sum = result.tallies[t.name];
        sum.name = t.name;
        sum.proposed += t.proposed;
        sum.accepted += t.accepted;
      }
      result.work += f.mutations;
      result.rays += f.rays;
      result.rejected += f.rejected;
      if (budget > 0) {
        double elapsed =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return elapsed < budget;
      }
      return true;
    });
  });
  result.image = job.resolve(sums, job.imageScale(result.bootstrap, result.work));
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace farm
