// An idle worker's lease waits at the coordinator for work: it gets a job's chains the moment
// the bootstrap ends or a lease expires, instead of on its next poll (where a second worker
// polling a moment later finds a short job already drained). Waits end early when the caller
// goes away or the server shuts down.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <thread>

#include "cli/local_chain_source.h"
#include "coordinator/coordinator.h"
#include "coordinator/coordinator_test_support.h"
#include "tests/test_support.h"
#include "worker/worker_pool.h"

namespace farm {
namespace {

using Clock = SteadyClock;
using std::chrono::milliseconds;
using std::chrono::seconds;

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

JobSpec smallJob() {
  JobSpec spec;
  spec.settings.algorithm = Algorithm::PSSMLT;
  spec.settings.width = 32;
  spec.settings.height = 32;
  spec.settings.mutationsPerPixel = 16;
  spec.settings.numChains = 2;
  spec.settings.bootstrapSamples = 20000;
  spec.settings.seed = 5;
  spec.scenePath = kScene;
  spec.name = "cornell";
  return spec;
}

// Milliseconds from `from` to `to` (steady clock ticks since its epoch).
double msBetween(Clock::duration from, Clock::duration to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

JobPhase phaseOf(const Coordinator& coordinator, const std::string& job) {
  JobProgress p;
  coordinator.progress(job, 0, &p);
  return p.phase;
}

class LeaseWait : public ::testing::Test {
 protected:
  LeaseWait() {
    options_.dataDir = scratch_.path();
    options_.leaseSeconds = 60;  // the tests expire leases with tick(later)
  }
  testing::ScratchDir scratch_{"lease-wait"};
  CoordinatorOptions options_;
};

TEST_F(LeaseWait, WaitingLeaseGetsTheChainsWhenTheBootstrapEnds) {
  Coordinator coordinator(options_);
  const std::string worker = registerTestWorker(coordinator, 2);
  std::string job;
  ASSERT_TRUE(coordinator.submit(smallJob(), &job).isOk());
  // Loading and the bootstrap (20000 candidates) are still ahead: only a wait gets chains, and
  // it gets them when the job starts rendering, not at its next once-a-second re-check.
  std::atomic<int64_t> answeredAt{0};
  auto waiter = std::async(std::launch::async, [&] {
    std::vector<WorkerLease> leases;
    Status s = coordinator.leaseChains(worker, 8, &leases, Coordinator::kMaxLeaseWait);
    answeredAt = Clock::now().time_since_epoch().count();
    EXPECT_TRUE(s.isOk()) << s.message();
    return leases;
  });
  Clock::time_point renderingSeen{};
  for (auto until = Clock::now() + seconds(30); Clock::now() < until;) {
    if (phaseOf(coordinator, job) == JobPhase::kRendering) {
      renderingSeen = Clock::now();
      break;
    }
    std::this_thread::sleep_for(milliseconds(2));
  }
  std::vector<WorkerLease> leases = waiter.get();
  ASSERT_EQ(leases.size(), 2u);
  EXPECT_EQ(leases[0].jobId, job);
  ASSERT_NE(renderingSeen, Clock::time_point{}) << "the job never started rendering";
  EXPECT_LT(msBetween(renderingSeen.time_since_epoch(), Clock::duration(answeredAt.load())), 500);
}

TEST_F(LeaseWait, ExpiredLeaseWakesAWaitingWorkerAtOnce) {
  Coordinator coordinator(options_);
  const std::string a = registerTestWorker(coordinator, 2), b = registerTestWorker(coordinator, 2);
  std::string job;
  ASSERT_TRUE(coordinator.submit(smallJob(), &job).isOk());
  std::vector<WorkerLease> held;
  ASSERT_TRUE(coordinator.leaseChains(a, 8, &held, Coordinator::kMaxLeaseWait).isOk());
  ASSERT_EQ(held.size(), 2u);

  // b waits while a holds both chains; a's leases expire (tick at a later time) and b gets
  // them. The wait re-checks on its own only once a second, so an answer well inside that
  // second is the expiry's wake-up.
  std::atomic<int64_t> answeredAt{0};
  auto waiter = std::async(std::launch::async, [&] {
    std::vector<WorkerLease> leases;
    Status s = coordinator.leaseChains(b, 8, &leases, seconds(8));
    answeredAt = Clock::now().time_since_epoch().count();
    EXPECT_TRUE(s.isOk()) << s.message();
    return leases;
  });
  std::this_thread::sleep_for(milliseconds(200));
  EXPECT_EQ(answeredAt.load(), 0) << "the wait answered before any chain was free";
  const auto expiredAt = Clock::now();
  coordinator.tick(expiredAt + seconds(61));
  std::vector<WorkerLease> leases = waiter.get();
  ASSERT_EQ(leases.size(), 2u);
  EXPECT_EQ(leases[0].lease.epoch, held[0].lease.epoch + 1);
  EXPECT_LT(msBetween(expiredAt.time_since_epoch(), Clock::duration(answeredAt.load())), 500);
}

TEST_F(LeaseWait, ShutdownAndAbandonedCallersEndTheWait) {
  Coordinator coordinator(options_);
  const std::string worker = registerTestWorker(coordinator, 2);
  std::vector<WorkerLease> leases;

  // No job at all: the caller goes away after 100 ms and the wait ends with it.
  std::atomic<bool> gone{false};
  auto start = Clock::now();
  auto abandoned = std::async(std::launch::async, [&] {
    return coordinator.leaseChains(worker, 8, &leases, seconds(10), [&] { return gone.load(); });
  });
  std::this_thread::sleep_for(milliseconds(100));
  gone = true;
  EXPECT_TRUE(abandoned.get().isOk());
  EXPECT_TRUE(leases.empty());
  EXPECT_LT(msBetween(start.time_since_epoch(), Clock::now().time_since_epoch()), 5000);

  // Released (the server shuts down): a wait in progress ends and later ones do not wait.
  start = Clock::now();
  auto waiting = std::async(std::launch::async, [&] {
    std::vector<WorkerLease> none;
    return coordinator.leaseChains(worker, 8, &none, seconds(10)).isOk() && none.empty();
  });
  std::this_thread::sleep_for(milliseconds(100));
  coordinator.releaseLeaseWaiters();
  EXPECT_TRUE(waiting.get());
  EXPECT_LT(msBetween(start.time_since_epoch(), Clock::now().time_since_epoch()),
            600);  // not at its once-a-second re-check
  start = Clock::now();
  ASSERT_TRUE(coordinator.leaseChains(worker, 8, &leases, seconds(10)).isOk());
  EXPECT_LT(msBetween(start.time_since_epoch(), Clock::now().time_since_epoch()), 500);
}

TEST_F(LeaseWait, StoppingAnEmbeddedWorkerEndsItsWait) {
  // `farm render` stops its pool when the job ends; an idle pool is then waiting at the
  // coordinator, and the render must not wait out that wait.
  Coordinator coordinator(options_);
  LocalChainSource source(&coordinator, 2);
  WorkerPoolOptions poolOptions;
  poolOptions.threads = 2;
  poolOptions.leaseWaitSeconds = 5;
  WorkerPool pool(&source, poolOptions);
  std::thread runner([&] { pool.run(); });
  std::this_thread::sleep_for(milliseconds(200));
  const auto start = Clock::now();
  pool.stop();
  runner.join();
  EXPECT_LT(msBetween(start.time_since_epoch(), Clock::now().time_since_epoch()), 500);
}

}  // namespace
}  // namespace farm
