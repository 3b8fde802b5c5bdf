// Chains are work units that must behave the same wherever and however often they run: the
// seed vector rebuilds the bootstrap's path exactly, a chain resumed from a flush's state
// continues bit for bit, and the primary-sample sampler's rejection restores its state.
#include "common/mcmc/pssmlt_chain.h"

#include <gtest/gtest.h>

#include <atomic>

#include "common/chain/resume_check.h"
#include "common/mcmc/bootstrap.h"
#include "common/mcmc/primary_sample_sampler.h"
#include "common/render/render_job.h"
#include "common/scene/scene.h"

namespace farm {
namespace {

const std::string kCornell = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

RenderSettings smallSettings() {
  RenderSettings s;
  s.algorithm = Algorithm::PSSMLT;
  s.width = 32;
  s.height = 32;
  s.mutationsPerPixel = 8;
  s.bootstrapSamples = 4096;
  s.numChains = 4;
  s.seed = 3;
  return s;
}

TEST(PrimarySampleSampler, RejectRestoresAndStateRoundTrips) {
  PrimarySampleSampler a(1, 2, 0.3f);
  a.setSeed({0.1f, 0.2f, 0.3f, 0.4f});
  a.startIteration();
  float v0 = a.next(kCameraStream), v1 = a.next(kLightStream);
  (void)v0;
  (void)v1;
  a.reject();
  a.setFrozen(true);
  a.startPath();
  EXPECT_EQ(a.next(kCameraStream), 0.1f);  // the rejected proposal left no trace
  EXPECT_EQ(a.next(kLightStream), 0.2f);
  a.setFrozen(false);
  for (int i = 0; i < 50; ++i) {
    a.startIteration();
    for (int k = 0; k < 6; ++k) a.next(SampleStream(k % 2));
    if (i % 3)
      a.accept();
    else
      a.reject();
  }
  PrimarySampleSampler b(99, 99, 0.3f);
  ASSERT_TRUE(b.deserialize(a.serialize()));
  for (int i = 0; i < 20; ++i) {
    a.startIteration();
    b.startIteration();
    for (int k = 0; k < 8; ++k) EXPECT_EQ(a.next(SampleStream(k % 2)), b.next(SampleStream(k % 2)));
    a.accept();
    b.accept();
  }
  EXPECT_FALSE(b.deserialize("not a state"));
}

TEST(PssmltChain, SeedRebuildsTheBootstrapPath) {
  RenderSettings s = smallSettings();
  auto scene = loadScene(kCornell, s);
  RenderJob job(scene, s, "seed");
  BootstrapResult boot = job.bootstrap();
  ASSERT_EQ(boot.seedSamples.size(), 4u);
  std::vector<ChainSpec> specs = job.planChains(boot);
  for (size_t i = 0; i < specs.size(); ++i) {
    EXPECT_GT(specs[i].seedContribution, 0);
    EXPECT_EQ(seedContributionOf(*scene, specs[i]), specs[i].seedContribution);
  }
  EXPECT_GT(boot.normalization, 0);
  EXPECT_GT(boot.normalizationStdError, 0);
  EXPECT_LT(boot.normalizationStdError, boot.normalization);
}

TEST(PssmltChain, ResumedChainContinuesExactly) {
  RenderSettings s = smallSettings();
  auto scene = loadScene(kCornell, s);
  RenderJob job(scene, s, "resume");
  BootstrapResult boot = job.bootstrap();
  ChainSpec spec = job.planChains(boot)[1];
  spec.budget = 3000;
  spec.flushInterval = 1000;
  std::vector<ChainFlush> whole = expectResumesExactly(
      spec, 0, [&](const ChainSpec& c, const FlushSink& sink) { job.runChain(c, sink); });
  ASSERT_EQ(whole.size(), 3u);
  EXPECT_TRUE(whole.back().finished);

  ChainSpec corrupt = spec;
  corrupt.resumeState = "garbage";
  EXPECT_THROW(job.runChain(corrupt, [](ChainFlush&&) { return true; }), std::runtime_error);
}

TEST(PssmltChain, CancelStopsBeforeTheNextFlush) {
  RenderSettings s = smallSettings();
  auto scene = loadScene(kCornell, s);
  RenderJob job(scene, s, "cancel");
  ChainSpec spec = job.planChains(job.bootstrap())[0];
  spec.budget = 1000000;
  spec.flushInterval = 1000;
  std::atomic<bool> cancel{false};
  int flushes = 0;
  job.runChain(
      spec,
      [&](ChainFlush&&) {
        ++flushes;
        cancel = true;  // e.g. the worker is shutting down
        return true;
      },
      &cancel);
  EXPECT_EQ(flushes, 1);
}

TEST(PssmltChain, NoLightGivesAClearError) {
  RenderSettings s = smallSettings();
  auto scene = loadScene(kCornell, s);
  // The same box with its light switched off: no emitters at all.
  SceneDescription dark = scene->description();
  for (ShapeDescription& shape : dark.shapes) shape.isEmitter = false;
  RenderJob darkJob(std::make_shared<Scene>(dark), s, "dark");
  try {
    darkJob.bootstrap();
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no light reaches the camera"), std::string::npos)
        << e.what();
  }
  // A lit box, but the camera turned around: it looks into the void, no path carries light.
  SceneDescription away = scene->description();
  away.camera.toWorld = Matrix4::translate(Vec3f(0, 1, 6.8f));
  RenderJob awayJob(std::make_shared<Scene>(away), s, "away");
  try {
    awayJob.bootstrap();
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no light reaches the camera"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace farm
