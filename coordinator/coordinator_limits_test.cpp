// What a coordinator holds at once: a submit beyond --max-jobs unfinished jobs is refused with
// a reason, loses nothing already accepted, and is taken again once a job ends.
#include <gtest/gtest.h>

#include "coordinator/coordinator.h"
#include "tests/test_support.h"

namespace farm {
namespace {

JobSpec queuedJob() {
  JobSpec spec;
  spec.settings.algorithm = Algorithm::PathTracing;
  spec.settings.width = 16;
  spec.settings.height = 16;
  spec.settings.samplesPerPixel = 1 << 20;  // no worker: it stays queued
  spec.scenePath = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";
  spec.name = "queued";
  return spec;
}

TEST(CoordinatorLimits, ASubmitBeyondMaxJobsIsRefusedUntilOneEnds) {
  testing::ScratchDir scratch("limits");
  CoordinatorOptions options;
  options.dataDir = scratch.path();
  options.maxActiveJobs = 2;
  Coordinator coordinator(options);
  std::string first, second, third;
  ASSERT_TRUE(coordinator.submit(queuedJob(), &first).isOk());
  ASSERT_TRUE(coordinator.submit(queuedJob(), &second).isOk());
  Status refused = coordinator.submit(queuedJob(), &third);
  EXPECT_EQ(refused.code(), StatusCode::kResourceExhausted);
  EXPECT_NE(refused.message().find("--max-jobs 2"), std::string::npos) << refused.message();
  EXPECT_EQ(coordinator.list().size(), 2u) << "the refusal must not touch the accepted jobs";

  JobPhase phase;
  ASSERT_TRUE(coordinator.cancel(first, &phase).isOk());
  EXPECT_TRUE(coordinator.submit(queuedJob(), &third).isOk()) << "a cancelled job no longer counts";
  EXPECT_EQ(coordinator.list().size(), 3u);
}

}  // namespace
}  // namespace farm
