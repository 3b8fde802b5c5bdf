// The coordinator core with the real renderer: a chain whose worker vanishes after one flush is
// re-leased when the lease expires, resumes from that flush's state, and the job's image equals
// the image of an uninterrupted run (DESIGN.md: a dead worker costs at most one flush interval,
// and failures do not change the image).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <thread>

#include "coordinator/coordinator.h"
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
  std::string id;
  Status s = coordinator.submit(spec, &id);
  EXPECT_TRUE(s.isOk()) << s.message();
  for (int i = 0; i < 1200; ++i) {
    JobProgress p;
    coordinator.progress(id, 0, &p);
    if (p.phase == JobPhase::kRendering) return id;
    EXPECT_FALSE(isTerminal(p.phase)) << p.error;
    if (isTerminal(p.phase)) return id;
    std::this_thread::sleep_for(milliseconds(50));
  }
  ADD_FAILURE() << "job did not start rendering";
  return id;
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

std::string registerWorker(Coordinator& coordinator) {
  WorkerInfo info;
  info.threads = 1;
  for (Algorithm a : allAlgorithms()) info.capabilities.insert(a);
  std::string id;
  EXPECT_TRUE(coordinator.registerWorker(info, &id).isOk());
  return id;
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
  const std::string workerA = registerWorker(coordinator);
  std::vector<WorkerLease> leases;
  ASSERT_TRUE(coordinator.leaseChains(workerA, 8, &leases).isOk());
  ASSERT_EQ(leases.size(), 2u);
  for (const WorkerLease& lease : leases) EXPECT_EQ(runLease(coordinator, workerA, lease, 99), 2);
  const Image expected = finish(coordinator, straight);

  // Interrupted run: chain 0's worker vanishes after its first flush.
  const std::string interrupted = submitAndWait(coordinator, settings);
  const std::string workerB = registerWorker(coordinator);
  ASSERT_TRUE(coordinator.leaseChains(workerB, 8, &leases).isOk());
  ASSERT_EQ(leases.size(), 2u);
  EXPECT_EQ(runLease(coordinator, workerB, leases[0], 1), 1);
  EXPECT_EQ(runLease(coordinator, workerB, leases[1], 99), 2);
  JobProgress p;
  coordinator.progress(interrupted, 0, &p);
  EXPECT_EQ(p.phase, JobPhase::kRendering);
  EXPECT_EQ(p.workDone, 4096 + 8192);

  // Nothing to lease until the lease expires; then chain 0 comes back at flush 1.
  const std::string workerC = registerWorker(coordinator);
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

}  // namespace
}  // namespace farm
