// proto/convert.h: the job phase, the one enum the coordinator, the store and the clients all
// report, crosses the wire and comes back as itself (what a newer or broken peer sends that this
// build does not know reads as submitted); so do the settings and work units of Kelemen's
// combined large steps.
#include "proto/convert.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

namespace farm {
namespace {

TEST(Convert, EveryJobPhaseCrossesTheWireAndBack) {
  std::set<int> wire;
  for (JobPhase p : {JobPhase::kSubmitted, JobPhase::kLoadingScene, JobPhase::kBootstrapping,
                     JobPhase::kRendering, JobPhase::kFinishing, JobPhase::kDone, JobPhase::kFailed,
                     JobPhase::kCancelled}) {
    const v1::JobPhase m = toProto(p);
    EXPECT_NE(m, v1::PHASE_UNSPECIFIED) << jobPhaseName(p);
    EXPECT_TRUE(wire.insert(int(m)).second) << jobPhaseName(p) << " shares its wire value";
    EXPECT_EQ(fromProto(m), p) << jobPhaseName(p);
  }
  EXPECT_EQ(fromProto(v1::PHASE_UNSPECIFIED), JobPhase::kSubmitted);
  EXPECT_EQ(fromProto(static_cast<v1::JobPhase>(99)), JobPhase::kSubmitted);
}

// Kelemen's combination crosses the wire as a setting and as each chain's weight, and a chain
// whose weight no honest coordinator sends is refused.
TEST(Convert, CombinedLargeStepsCrossTheWire) {
  RenderSettings settings;
  settings.combineLargeSteps = true;
  RenderSettings back;
  std::string error;
  ASSERT_TRUE(fromProto(toProto(settings), &back, &error)) << error;
  EXPECT_TRUE(back.combineLargeSteps);

  ChainSpec spec;
  spec.flushInterval = 100;
  spec.largeStepMis = 0.75;
  ChainSpec chain;
  ASSERT_TRUE(fromProto(toProto(spec), &chain, &error)) << error;
  EXPECT_EQ(chain.largeStepMis, 0.75);
  for (double bad : {-1.0, std::nan(""), HUGE_VAL}) {
    spec.largeStepMis = bad;
    EXPECT_FALSE(fromProto(toProto(spec), &chain, &error)) << bad;
    EXPECT_NE(error.find("large-step weight"), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace farm
