// The coordinator core with the real renderer: a chain whose worker vanishes after one flush is
// re-leased when the lease expires, resumes from that flush's state, and the job's image equals
// the image of an uninterrupted run (docs/design.md: a dead worker costs at most one flush
// interval, and failures do not change the image).
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

#include "coordinator/coordinator.h"
#include "coordinator/coordinator_test_support.h"
#include "coordinator/job_store.h"
#include "tests/test_support.h"

namespace farm {
namespace {

using std::chrono::milliseconds;

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

RenderSettings smallJob(Algorithm algorithm) {
  RenderSettings s;
  s.algorithm = algorithm;
  s.width = 32;
  s.height = 32;
  // 32*32*16 = 16384 over 2 chains: 8192 each, flushed every 4096 (the renderer's minimum).
  s.samplesPerPixel = 16;
  s.mutationsPerPixel = 16;
  s.numChains = 2;
  s.bootstrapSamples = 20000;
  s.seed = 11;
  return s;
}

std::string submitAndWait(Coordinator& coordinator, const RenderSettings& settings) {
  JobSpec spec;
  spec.settings = settings;
  spec.scenePath = kScene;
  spec.name = "cornell";
  return submitAndWaitForRendering(coordinator, spec);
}

// Runs a leased chain; uploads at most `maxFlushes` flushes (then "dies").
int runLease(Coordinator& coordinator, const std::string& worker, const WorkerLease& lease,
             int maxFlushes, std::vector<FlushAck>* acks = nullptr) {
  auto job = coordinator.renderJob(lease.jobId);
  EXPECT_TRUE(job);
  int uploaded = 0;
  job->runChain(lease.lease.spec, [&](ChainFlush&& flush) {
    if (uploaded >= maxFlushes) return false;
    FlushAck ack;
    Status s =
        coordinator.acceptFlush(worker, lease.jobId, lease.lease.epoch, std::move(flush), &ack);
    EXPECT_TRUE(s.isOk()) << s.message();
    if (acks) acks->push_back(ack);
    ++uploaded;
    return !ack.stop;
  });
  return uploaded;
}

Image finish(Coordinator& coordinator, const std::string& job) {
  JobPhase phase;
  coordinator.waitForEnd(job, std::chrono::seconds(30), &phase);
  EXPECT_EQ(phase, JobPhase::kDone);
  Image image;
  Status s = coordinator.finalImage(job, &image, nullptr);
  EXPECT_TRUE(s.isOk()) << s.message();
  return image;
}

}  // namespace

void PrintTo(Algorithm a, std::ostream* os) {
  *os << algorithmName(a);
}

namespace {

class ResumeTest : public ::testing::TestWithParam<Algorithm> {};

TEST_P(ResumeTest, ReleasedChainResumesAndTheImageIsUnchanged) {
  testing::ScratchDir scratch("resume");
  CoordinatorOptions options;
  options.dataDir = scratch.path();
  // Long enough for slow (sanitizer) builds; the test makes the lease expire with tick(later).
  options.leaseSeconds = 60;
  Coordinator coordinator(options);
  const RenderSettings settings = smallJob(GetParam());

  // Uninterrupted reference run.
  const std::string straight = submitAndWait(coordinator, settings);
  const std::string workerA = registerTestWorker(coordinator, 1);
  std::vector<WorkerLease> leases;
  ASSERT_TRUE(coordinator.leaseChains(workerA, 8, &leases).isOk());
  ASSERT_EQ(leases.size(), 2u);
  for (const WorkerLease& lease : leases) EXPECT_EQ(runLease(coordinator, workerA, lease, 99), 2);
  const Image expected = finish(coordinator, straight);

  // Interrupted run: chain 0's worker vanishes after its first flush.
  const std::string interrupted = submitAndWait(coordinator, settings);
  const std::string workerB = registerTestWorker(coordinator, 1);
  ASSERT_TRUE(coordinator.leaseChains(workerB, 8, &leases).isOk());
  ASSERT_EQ(leases.size(), 2u);
  EXPECT_EQ(runLease(coordinator, workerB, leases[0], 1), 1);
  EXPECT_EQ(runLease(coordinator, workerB, leases[1], 99), 2);
  JobProgress p;
  coordinator.progress(interrupted, 0, &p);
  EXPECT_EQ(p.phase, JobPhase::kRendering);
  EXPECT_EQ(p.workDone, 4096 + 8192);

  // Nothing to lease until the lease expires; then chain 0 comes back at flush 1.
  const std::string workerC = registerTestWorker(coordinator, 1);
  ASSERT_TRUE(coordinator.leaseChains(workerC, 8, &leases).isOk());
  EXPECT_TRUE(leases.empty());
  coordinator.tick(SteadyClock::now() + std::chrono::seconds(61));
  ASSERT_TRUE(coordinator.leaseChains(workerC, 8, &leases).isOk());
  ASSERT_EQ(leases.size(), 1u);
  const ChainSpec& resumed = leases[0].lease.spec;
  EXPECT_EQ(resumed.chainIndex, 0u);
  EXPECT_EQ(resumed.resumeFlushIndex, 1u);
  EXPECT_EQ(resumed.resumeMutations, 4096);
  EXPECT_FALSE(resumed.resumeState.empty());
  EXPECT_EQ(runLease(coordinator, workerC, leases[0], 99), 1);
  const Image actual = finish(coordinator, interrupted);

  ASSERT_EQ(actual.rgb.size(), expected.rgb.size());
  double worst = 0;
  for (size_t i = 0; i < actual.rgb.size(); ++i) {
    ASSERT_TRUE(std::isfinite(actual.rgb[i]));
    if (std::abs(expected.rgb[i]) > 1e-3) {
      worst = std::max(
          worst, double(std::abs(actual.rgb[i] - expected.rgb[i]) / std::abs(expected.rgb[i])));
    }
  }
  EXPECT_LT(worst, 1e-5);
}

INSTANTIATE_TEST_SUITE_P(Algorithms, ResumeTest,
                         ::testing::Values(Algorithm::PathTracing, Algorithm::PSSMLT,
                                           Algorithm::PSSMLTOverPT, Algorithm::MMLT,
                                           Algorithm::MLT),
                         [](const auto& info) {
                           std::string name = algorithmName(info.param);
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

// A durable coordinator (--data) that goes away at any point and is started again on the same
// directory goes on with every job from its last acknowledged flush: the chains resume there,
// a flush accepted before the restart is a duplicate after it, and the image is the one of an
// uninterrupted run. Twice restarted mid-job (the second restart reads a checkpoint and replays
// the log after it), once after the end.
struct DurableCase {
  Algorithm algorithm;
  uint64_t checkpointBytes;  // 0: the default (here: replay the log); 1: after every flush
};

class DurableResumeTest : public ::testing::TestWithParam<DurableCase> {};

double worstRelativeDifference(const Image& actual, const Image& expected) {
  EXPECT_EQ(actual.rgb.size(), expected.rgb.size());
  double worst = 0;
  for (size_t i = 0; i < std::min(actual.rgb.size(), expected.rgb.size()); ++i) {
    if (!std::isfinite(actual.rgb[i])) return INFINITY;
    if (std::abs(expected.rgb[i]) > 1e-3) {
      worst = std::max(
          worst, double(std::abs(actual.rgb[i] - expected.rgb[i]) / std::abs(expected.rgb[i])));
    }
  }
  return worst;
}

TEST_P(DurableResumeTest, RestartedCoordinatorGoesOnFromItsLastFlush) {
  testing::ScratchDir scratch("durable");
  RenderSettings settings = smallJob(GetParam().algorithm);
  settings.samplesPerPixel = 32;  // 2 chains of 16384: four flushes each
  settings.mutationsPerPixel = 32;

  Image expected;
  {
    CoordinatorOptions options;
    options.dataDir = scratch / "straight";
    Coordinator coordinator(options);
    const std::string job = submitAndWait(coordinator, settings);
    const std::string worker = registerTestWorker(coordinator, 1);
    std::vector<WorkerLease> leases;
    ASSERT_TRUE(coordinator.leaseChains(worker, 8, &leases).isOk());
    for (const WorkerLease& lease : leases) EXPECT_EQ(runLease(coordinator, worker, lease, 99), 4);
    expected = finish(coordinator, job);
  }

  CoordinatorOptions options;
  options.dataDir = scratch / "durable";
  options.durable = true;
  options.checkpointBytes = GetParam().checkpointBytes;
  options.leaseSeconds = 60;
  std::string job, oldWorker;
  std::vector<WorkerLease> oldLeases;
  ChainFlush replayed;  // flush 0 of chain 0, to deliver again after the restart
  {
    Coordinator first(options);
    EXPECT_TRUE(first.durable());
    job = submitAndWait(first, settings);
    oldWorker = registerTestWorker(first, 1);
    ASSERT_TRUE(first.leaseChains(oldWorker, 8, &oldLeases).isOk());
    ASSERT_EQ(oldLeases.size(), 2u);
    auto renderJob = first.renderJob(job);
    renderJob->runChain(oldLeases[0].lease.spec, [&](ChainFlush&& flush) {
      replayed = flush;
      FlushAck ack;
      EXPECT_TRUE(
          first.acceptFlush(oldWorker, job, oldLeases[0].lease.epoch, std::move(flush), &ack)
              .isOk());
      EXPECT_EQ(ack.result, FlushAck::Result::kAccepted);
      return false;
    });
    EXPECT_EQ(runLease(first, oldWorker, oldLeases[1], 1), 1);
  }  // gone: nothing more reaches its database than what it acknowledged

  // Killed between appending flushes to the log and committing their rows: the log holds
  // records that no row points at (here a second copy of every committed one, or a torn
  // record), which must count for nothing.
  {
    const std::string log = scratch / ("durable/logs/" + job + ".log");
    ASSERT_TRUE(std::filesystem::exists(log));
    std::string bytes = testing::readFile(log);
    std::ofstream(log, std::ios::binary | std::ios::app)
        << (bytes.empty() ? std::string(1000, '\x7f') : bytes);
  }
  // Checkpoint films beside the database: the one a checkpoint record names, and leftovers of
  // a crash between writing one and committing its record, which a restart removes.
  const std::string logs = scratch / "durable/logs";
  auto films = [&] {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(logs)) {
      const std::string name = e.path().filename().string();
      if (name.find(".sums") != std::string::npos) names.push_back(name);
    }
    return names;
  };
  std::ofstream(logs + "/" + job + ".0.7.sums") << "left by a crash";
  std::ofstream(logs + "/" + job + ".0.8.sums.tmp") << "left by a crash";
  for (int restart = 1; restart <= 2; ++restart) {
    SCOPED_TRACE("restart " + std::to_string(restart));
    Coordinator again(options);
    // Each restart replays a log and folds it into a checkpoint: its film, and nothing else.
    const std::vector<std::string> kept = films();
    ASSERT_EQ(kept.size(), 1u) << (kept.empty() ? "" : kept[0]);
    EXPECT_EQ(kept[0].rfind(job + ".", 0), 0u) << kept[0];
    EXPECT_GT(std::filesystem::file_size(logs + "/" + kept[0]), 0u);
    JobProgress p;
    ASSERT_TRUE(again.progress(job, 0, &p).isOk());
    EXPECT_EQ(p.phase, JobPhase::kRendering) << p.error;
    EXPECT_EQ(p.workDone, 2 * 4096 * restart) << "work accepted before the restart";
    EXPECT_EQ(p.chainsTotal, 2u);
    if (GetParam().algorithm != Algorithm::PathTracing) {
      EXPECT_GT(p.normalization, 0) << "the plan's Z";
    }
    if (GetParam().algorithm == Algorithm::PSSMLT) {
      // Z pools them: lost in a restart, the image would differ from the straight run's.
      EXPECT_GT(p.largeSteps, 0) << "the large steps accepted before the restart";
    }

    // The old worker's id means nothing now (it registers again); the flush it delivered
    // before the restart is known.
    std::vector<WorkerLease> leases;
    EXPECT_EQ(again.leaseChains(oldWorker, 8, &leases).code(), StatusCode::kNotFound);
    const std::string worker = registerTestWorker(again, 1);
    FlushAck ack;
    ChainFlush copy = replayed;
    ASSERT_TRUE(
        again.acceptFlush(worker, job, oldLeases[0].lease.epoch, std::move(copy), &ack).isOk());
    EXPECT_EQ(ack.result, FlushAck::Result::kDuplicate);

    ASSERT_TRUE(again.leaseChains(worker, 8, &leases).isOk());
    ASSERT_EQ(leases.size(), 2u);
    for (const WorkerLease& lease : leases) {
      EXPECT_EQ(lease.lease.spec.resumeFlushIndex, uint32_t(restart));
      EXPECT_EQ(lease.lease.spec.resumeMutations, 4096 * restart);
      EXPECT_GT(lease.lease.epoch, oldLeases[0].lease.epoch) << "an epoch of the old run again";
    }
    // Wait for the scene (it loads again on the job's thread) before running chains here.
    for (int i = 0; i < 600 && !again.renderJob(job); ++i) {
      std::this_thread::sleep_for(milliseconds(50));
    }
    ASSERT_TRUE(again.renderJob(job));
    if (restart == 1) {
      for (const WorkerLease& lease : leases) EXPECT_EQ(runLease(again, worker, lease, 1), 1);
    } else {
      for (const WorkerLease& lease : leases) EXPECT_EQ(runLease(again, worker, lease, 99), 2);
      EXPECT_LT(worstRelativeDifference(finish(again, job), expected), 1e-5);
      EXPECT_TRUE(films().empty()) << "the job ended: its film is in its image now";
    }
  }

  // After the end: the job is done, with its image and its counts.
  Coordinator after(options);
  JobProgress p;
  ASSERT_TRUE(after.progress(job, 0, &p).isOk());
  EXPECT_EQ(p.phase, JobPhase::kDone) << p.error;
  EXPECT_EQ(p.workDone, 32 * 32 * 32);
  EXPECT_DOUBLE_EQ(p.fraction, 1.0);
  EXPECT_TRUE(films().empty()) << "an ended job keeps its image, not its film";
  Image image;
  ASSERT_TRUE(after.finalImage(job, &image, nullptr).isOk());
  EXPECT_LT(worstRelativeDifference(image, expected), 1e-5);
}

INSTANTIATE_TEST_SUITE_P(
    Algorithms, DurableResumeTest,
    ::testing::Values(DurableCase{Algorithm::PathTracing, 0},
                      DurableCase{Algorithm::PathTracing, 1}, DurableCase{Algorithm::MLT, 0},
                      DurableCase{Algorithm::PSSMLT, 0}, DurableCase{Algorithm::PSSMLT, 1}),
    [](const auto& info) {
      std::string name = algorithmName(info.param.algorithm);
      std::replace(name.begin(), name.end(), '-', '_');
      return name + (info.param.checkpointBytes ? "_checkpoint_every_flush" : "_log_replay");
    });

// --algorithm auto on a durable coordinator: the pilot picks once, the chains run the pick, the
// job's progress carries the plan, and a restart goes on with the same pick and plan instead
// of piloting again (whose figures, and perhaps pick, would differ).
TEST(DurableResumeAuto, ARestartKeepsThePilotsPickAndThePlan) {
  testing::ScratchDir scratch("durable-auto");
  RenderSettings settings = smallJob(Algorithm::PSSMLT);
  settings.autoAlgorithm = true;
  settings.pilot = true;
  CoordinatorOptions options;
  options.dataDir = scratch / "data";
  options.durable = true;
  std::string job;
  JobProgress before;
  {
    Coordinator first(options);
    job = submitAndWait(first, settings);
    ASSERT_TRUE(first.progress(job, 0, &before).isOk());
    EXPECT_FALSE(before.settings.autoAlgorithm);
    std::string plan;
    for (const std::string& line : before.renderPlan) plan += line + "\n";
    EXPECT_NE(plan.find("(auto)"), std::string::npos) << plan;
    EXPECT_NE(plan.find("pilot "), std::string::npos) << plan;
    EXPECT_NE(plan.find(std::string("algorithm: ") + algorithmName(before.settings.algorithm)),
              std::string::npos)
        << plan;
    const std::string worker = registerTestWorker(first, 1);
    std::vector<WorkerLease> leases;
    ASSERT_TRUE(first.leaseChains(worker, 8, &leases).isOk());
    ASSERT_FALSE(leases.empty());
    for (const WorkerLease& lease : leases)
      EXPECT_EQ(lease.lease.spec.algorithm, before.settings.algorithm);
  }
  Coordinator again(options);
  JobProgress after;
  ASSERT_TRUE(again.progress(job, 0, &after).isOk());
  EXPECT_EQ(after.phase, JobPhase::kRendering) << after.error;
  EXPECT_EQ(after.settings.algorithm, before.settings.algorithm);
  EXPECT_FALSE(after.settings.autoAlgorithm) << "the planned settings, not the submitted ones";
  EXPECT_EQ(after.renderPlan, before.renderPlan);
  const std::string worker = registerTestWorker(again, 1);
  std::vector<WorkerLease> leases;
  ASSERT_TRUE(again.leaseChains(worker, 8, &leases).isOk());
  ASSERT_FALSE(leases.empty());
  for (const WorkerLease& lease : leases)
    EXPECT_EQ(lease.lease.spec.algorithm, before.settings.algorithm);
}

// --algorithm auto where the plan renders bdpt with a time budget: the allocation pilot's
// samples are the image's first (algorithm_pilot.h, PilotSamples), durable as the job's first
// checkpoint, and a restart counts them once, before any flush and after flushes replayed from
// the log.
TEST(DurableResumeAuto, TheAllocationPilotsSamplesCountOnceAcrossRestarts) {
  testing::ScratchDir scratch("durable-pilot");
  JobSpec spec;
  spec.settings.autoAlgorithm = true;
  spec.settings.width = spec.settings.height = 32;
  spec.settings.timeBudgetSeconds = 20;  // a pilot of 2 s; the restarts take far less
  spec.settings.numChains = 2;
  spec.settings.seed = 11;
  spec.scenePath = std::string(FARM_TEST_DATA_DIR) + "/smoky-box/scene.xml";
  spec.name = "smoky-box";
  CoordinatorOptions options;
  options.dataDir = scratch / "data";
  options.durable = true;
  options.leaseSeconds = 60;
  std::string job;
  int64_t pilot = 0;
  Image pilotImage, flushedImage;
  // The image a restarted coordinator resolves, once its scene has loaded again.
  auto imageOf = [&](Coordinator& c) {
    for (int i = 0; i < 600 && !c.renderJob(job); ++i)
      std::this_thread::sleep_for(milliseconds(50));
    Image image;
    EXPECT_TRUE(c.currentImage(job, &image).isOk());
    return image;
  };
  {
    Coordinator first(options);
    job = submitAndWaitForRendering(first, spec);
    JobProgress p;
    ASSERT_TRUE(first.progress(job, 0, &p).isOk());
    std::string plan;
    for (const std::string& line : p.renderPlan) plan += line + "\n";
    ASSERT_EQ(p.settings.algorithm, Algorithm::Bidirectional) << plan;
    ASSERT_TRUE(p.settings.pixelAllocation) << plan;
    pilot = p.pilotWork;
    EXPECT_GT(pilot, 0) << plan;
    EXPECT_EQ(p.workDone, pilot) << "no chain has flushed yet";
    EXPECT_EQ(p.samplesPerSecond, 0) << "the rate is the chains' own";
    ASSERT_TRUE(first.currentImage(job, &pilotImage).isOk()) << "the pilot's samples alone";
  }
  int64_t flushed = 0;
  {
    Coordinator again(options);
    JobProgress p;
    ASSERT_TRUE(again.progress(job, 0, &p).isOk());
    ASSERT_EQ(p.phase, JobPhase::kRendering) << p.error;
    EXPECT_EQ(p.pilotWork, pilot) << "the pilot's samples, from the job's first checkpoint";
    EXPECT_EQ(p.workDone, pilot);
    EXPECT_LT(worstRelativeDifference(imageOf(again), pilotImage), 1e-6) << "its film too";
    const std::string worker = registerTestWorker(again, 1);
    std::vector<WorkerLease> leases;
    ASSERT_TRUE(again.leaseChains(worker, 8, &leases).isOk());
    ASSERT_EQ(leases.size(), 2u);
    for (int i = 0; i < 600 && !again.renderJob(job); ++i)
      std::this_thread::sleep_for(milliseconds(50));
    ASSERT_TRUE(again.renderJob(job));
    for (const WorkerLease& lease : leases) {
      again.renderJob(job)->runChain(lease.lease.spec, [&](ChainFlush&& flush) {
        const int64_t mutations = flush.mutations;
        FlushAck ack;
        EXPECT_TRUE(
            again.acceptFlush(worker, job, lease.lease.epoch, std::move(flush), &ack).isOk());
        EXPECT_EQ(ack.result, FlushAck::Result::kAccepted);
        flushed += mutations;
        return false;  // one flush, then the worker "dies"
      });
    }
    ASSERT_GT(flushed, 0);
    ASSERT_TRUE(again.progress(job, 0, &p).isOk());
    EXPECT_EQ(p.workDone, pilot + flushed);
    EXPECT_EQ(p.pilotWork, pilot);
    flushedImage = imageOf(again);
  }
  Coordinator third(options);  // the checkpoint (the pilot's), then the log of the two flushes
  JobProgress p;
  ASSERT_TRUE(third.progress(job, 0, &p).isOk());
  ASSERT_EQ(p.phase, JobPhase::kRendering) << p.error;
  EXPECT_EQ(p.workDone, pilot + flushed) << "the pilot's samples counted once";
  EXPECT_EQ(p.pilotWork, pilot);
  EXPECT_LT(worstRelativeDifference(imageOf(third), flushedImage), 1e-6);
}

// Every fault counts once (issue 8): a late flush from a worker whose lease moved on is the
// chain's next flush or a duplicate, never a second copy, and its sender is told to stop;
// whichever of the two workers delivers first, the image is the uninterrupted run's.
TEST(FaultsCountOnce, LateFlushFromAnOlderLease) {
  testing::ScratchDir scratch("late-flush");
  CoordinatorOptions options;
  options.dataDir = scratch.path();
  options.leaseSeconds = 60;
  Coordinator coordinator(options);
  const RenderSettings settings = smallJob(Algorithm::PSSMLT);

  const std::string straight = submitAndWait(coordinator, settings);
  const std::string worker = registerTestWorker(coordinator, 1);
  std::vector<WorkerLease> leases;
  ASSERT_TRUE(coordinator.leaseChains(worker, 8, &leases).isOk());
  for (const WorkerLease& lease : leases) EXPECT_EQ(runLease(coordinator, worker, lease, 99), 2);
  const Image expected = finish(coordinator, straight);

  for (bool lateFirst : {true, false}) {
    SCOPED_TRACE(lateFirst ? "the late flush first" : "the new holder first");
    const std::string job = submitAndWait(coordinator, settings);
    const std::string slow = registerTestWorker(coordinator, 1);
    const std::string fresh = registerTestWorker(coordinator, 1);
    std::vector<WorkerLease> old, now;
    ASSERT_TRUE(coordinator.leaseChains(slow, 8, &old).isOk());
    ASSERT_EQ(old.size(), 2u);
    // The slow worker's leases expire; the chains go to the fresh one under a newer epoch.
    coordinator.tick(SteadyClock::now() + std::chrono::seconds(61));
    ASSERT_TRUE(coordinator.leaseChains(fresh, 8, &now).isOk());
    ASSERT_EQ(now.size(), 2u);
    EXPECT_GT(now[0].lease.epoch, old[0].lease.epoch);

    std::vector<FlushAck> lateAcks;
    if (lateFirst) {
      EXPECT_EQ(runLease(coordinator, slow, old[0], 1, &lateAcks), 1);
    }
    std::vector<FlushAck> freshAcks;
    EXPECT_EQ(runLease(coordinator, fresh, now[0], 99, &freshAcks), 2);
    if (!lateFirst) {
      EXPECT_EQ(runLease(coordinator, slow, old[0], 1, &lateAcks), 1);
    }
    ASSERT_EQ(lateAcks.size(), 1u);
    ASSERT_EQ(freshAcks.size(), 2u);
    EXPECT_TRUE(lateAcks[0].stop) << "a worker without the lease must be told to stop";
    EXPECT_NE(lateAcks[0].reason.find("no longer holds the lease"), std::string::npos)
        << lateAcks[0].reason;
    // Exactly one of the two copies of flush 0 counted.
    EXPECT_EQ(lateAcks[0].result,
              lateFirst ? FlushAck::Result::kAccepted : FlushAck::Result::kDuplicate);
    EXPECT_EQ(freshAcks[0].result,
              lateFirst ? FlushAck::Result::kDuplicate : FlushAck::Result::kAccepted);
    EXPECT_EQ(freshAcks[1].result, FlushAck::Result::kAccepted);
    EXPECT_EQ(runLease(coordinator, fresh, now[1], 99), 2);
    JobProgress p;
    coordinator.progress(job, 0, &p);
    EXPECT_EQ(p.workDone, 32 * 32 * 16);
    EXPECT_LT(worstRelativeDifference(finish(coordinator, job), expected), 1e-5);
  }
}

// A worker that keeps failing a chain - its leases expire, or it sends malformed flushes - is
// set aside after --max-chain-failures tries: it gets none of the job's chains any more, the
// job's progress says which worker and why, and another worker finishes the job.
TEST(FaultsCountOnce, WorkerFailingAChainRepeatedlyIsSetAside) {
  testing::ScratchDir scratch("set-aside");
  CoordinatorOptions options;
  options.dataDir = scratch.path();
  options.leaseSeconds = 60;
  options.maxChainFailures = 2;
  Coordinator coordinator(options);
  const std::string job = submitAndWait(coordinator, smallJob(Algorithm::PathTracing));

  const std::string hanging = registerTestWorker(coordinator, 1);
  std::vector<WorkerLease> leases;
  auto later = SteadyClock::now();
  for (int attempt = 1; attempt <= 2; ++attempt) {
    ASSERT_TRUE(coordinator.leaseChains(hanging, 8, &leases).isOk());
    ASSERT_EQ(leases.size(), 2u) << "attempt " << attempt;
    later += std::chrono::seconds(61);
    coordinator.tick(later);
  }
  ASSERT_TRUE(coordinator.leaseChains(hanging, 8, &leases).isOk());
  EXPECT_TRUE(leases.empty()) << "a set-aside worker got chains again";

  // One that sends NaN twice for the same chain goes the same way.
  const std::string broken = registerTestWorker(coordinator, 1);
  ASSERT_TRUE(coordinator.leaseChains(broken, 1, &leases).isOk());
  ASSERT_EQ(leases.size(), 1u);
  for (int attempt = 1; attempt <= 2; ++attempt) {
    ChainFlush bad;
    bad.chainIndex = leases[0].lease.spec.chainIndex;
    bad.width = bad.height = 32;
    bad.mutations = 1;
    bad.splats.assign(32 * 32 * 3, std::nanf(""));
    FlushAck ack;
    EXPECT_EQ(
        coordinator.acceptFlush(broken, job, leases[0].lease.epoch, std::move(bad), &ack).code(),
        StatusCode::kInvalidArgument);
  }
  std::vector<WorkerLease> more;
  ASSERT_TRUE(coordinator.leaseChains(broken, 8, &more).isOk());
  EXPECT_TRUE(more.empty());

  JobProgress p;
  coordinator.progress(job, 0, &p);
  ASSERT_EQ(p.setAside.size(), 2u);
  const std::string all = p.setAside[0] + "\n" + p.setAside[1];
  EXPECT_NE(all.find(hanging), std::string::npos) << all;
  EXPECT_NE(all.find("lease expired"), std::string::npos) << all;
  EXPECT_NE(all.find(broken), std::string::npos) << all;
  EXPECT_NE(all.find("NaN"), std::string::npos) << all;

  // Someone else finishes it (the broken worker's lease expires first).
  coordinator.tick(later + std::chrono::seconds(61));
  const std::string good = registerTestWorker(coordinator, 1);
  ASSERT_TRUE(coordinator.leaseChains(good, 8, &leases).isOk());
  ASSERT_EQ(leases.size(), 2u);
  for (const WorkerLease& lease : leases) EXPECT_EQ(runLease(coordinator, good, lease, 99), 2);
  finish(coordinator, job);
}

// A chain that fails on every worker that runs it (a path that crashes the renderer, say) must
// not keep its job rendering for ever: once it has had three workers set aside, the job fails
// and says which chain and why. Two are not enough (the test above: a third worker finishes).
TEST(FaultsCountOnce, AChainThatFailsOnThreeWorkersFailsTheJob) {
  testing::ScratchDir scratch("chain-to-blame");
  CoordinatorOptions options;
  options.dataDir = scratch.path();
  options.leaseSeconds = 60;
  options.maxChainFailures = 1;
  Coordinator coordinator(options);
  const std::string job = submitAndWait(coordinator, smallJob(Algorithm::PathTracing));
  auto later = SteadyClock::now();
  for (int w = 1; w <= Job::kWorkersToBlameAChain; ++w) {
    JobProgress before;
    coordinator.progress(job, 0, &before);
    EXPECT_EQ(before.phase, JobPhase::kRendering) << "after " << w - 1 << " workers";
    const std::string worker = registerTestWorker(coordinator, 1);
    std::vector<WorkerLease> leases;
    ASSERT_TRUE(coordinator.leaseChains(worker, 8, &leases).isOk());
    ASSERT_EQ(leases.size(), 2u) << "worker " << w;
    later += std::chrono::seconds(61);
    coordinator.tick(later);  // the leases expire: each chain fails once on this worker
  }
  JobPhase phase;
  coordinator.waitForEnd(job, std::chrono::seconds(5), &phase);
  EXPECT_EQ(phase, JobPhase::kFailed);
  JobProgress p;
  coordinator.progress(job, 0, &p);
  EXPECT_NE(p.error.find("chain 0 failed 1 times on each of 3 workers"), std::string::npos)
      << p.error;
  EXPECT_NE(p.error.find("lease expired"), std::string::npos) << p.error;
}

TEST(CoordinatorCore, FailedSceneKeepsItsMessage) {
  testing::ScratchDir scratch("failed-scene");
  CoordinatorOptions options;
  options.dataDir = scratch.path();
  Coordinator coordinator(options);
  const std::string broken = scratch / "broken.xml";
  { std::ofstream(broken) << "<scene version=\"0.5.0\"><shape type=\"nonsense\"/></scene>\n"; }
  JobSpec spec;
  spec.settings = smallJob(Algorithm::PathTracing);
  spec.scenePath = broken;
  std::string id;
  ASSERT_TRUE(coordinator.submit(spec, &id).isOk());
  JobPhase phase;
  coordinator.waitForEnd(id, std::chrono::seconds(30), &phase);
  EXPECT_EQ(phase, JobPhase::kFailed);
  JobProgress p;
  coordinator.progress(id, 0, &p);
  EXPECT_NE(p.error.find("broken.xml"), std::string::npos) << p.error;
  std::string path;
  Status s = coordinator.imageFile(id, &path);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(s.message().find("failed"), std::string::npos);

  spec.settings.samplesPerPixel = -1;
  EXPECT_EQ(coordinator.submit(spec, &id).code(), StatusCode::kInvalidArgument);
  spec.settings = smallJob(Algorithm::PathTracing);
  spec.scenePath = scratch / "missing.xml";
  EXPECT_EQ(coordinator.submit(spec, &id).code(), StatusCode::kInvalidArgument);
}

// A database of an earlier schema (2: no reference-free error estimate) is brought to 4 on
// opening, its error samples kept and marked as without an estimate (3 to 4 changes the flush
// records' form alone, and the older forms still read: StoreRecords); one of an unknown version
// is refused, not guessed.
TEST(JobStoreSchema, AVersionTwoDatabaseIsBroughtToFour) {
  testing::ScratchDir scratch("schema");
  {
    std::unique_ptr<JobStore> store;
    ASSERT_TRUE(JobStore::open(scratch.path(), &store).isOk());
  }
  const std::string path = scratch / "coordinator.db";
  auto exec = [&](const std::string& sql) {
    sqlite3* db = nullptr;
    EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    char* message = nullptr;
    const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message);
    EXPECT_EQ(rc, SQLITE_OK) << sql << ": " << (message ? message : "");
    sqlite3_free(message);
    sqlite3_close(db);
  };
  auto query = [&](const std::string& sql) {
    sqlite3* db = nullptr;
    sqlite3_open(path.c_str(), &db);
    sqlite3_stmt* q = nullptr;
    double value = -99;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &q, nullptr) == SQLITE_OK &&
        sqlite3_step(q) == SQLITE_ROW)
      value = sqlite3_column_double(q, 0);
    sqlite3_finalize(q);
    sqlite3_close(db);
    return value;
  };
  exec(
      "ALTER TABLE errors DROP COLUMN estimated; UPDATE meta SET value = 2 WHERE key = 'schema';"
      "INSERT INTO errors(job, idx, elapsed, samples, rmse, relmse) VALUES('j', 0, 1, 2, 3, 4)");
  {
    std::unique_ptr<JobStore> store;
    Status opened = JobStore::open(scratch.path(), &store);
    ASSERT_TRUE(opened.isOk()) << opened.message();
  }
  EXPECT_EQ(query("SELECT value FROM meta WHERE key = 'schema'"), 4);
  EXPECT_EQ(query("SELECT estimated FROM errors WHERE job = 'j'"), -1);
  EXPECT_EQ(query("SELECT relmse FROM errors WHERE job = 'j'"), 4);

  exec("UPDATE meta SET value = 1 WHERE key = 'schema'");
  std::unique_ptr<JobStore> store;
  Status refused = JobStore::open(scratch.path(), &store);
  EXPECT_FALSE(refused.isOk());
  EXPECT_NE(refused.message().find("has schema version 1; this coordinator reads 4"),
            std::string::npos)
      << refused.message();
}

}  // namespace
}  // namespace farm
