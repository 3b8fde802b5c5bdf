// proto/convert.h: the job phase, the one enum the coordinator, the store and the clients all
// report, crosses the wire and comes back as itself; what a newer or broken peer sends that this
// build does not know reads as submitted.
#include "proto/convert.h"

#include <gtest/gtest.h>

#include <set>

namespace farm {
namespace {

TEST(Convert, EveryJobPhaseCrossesTheWireAndBack) {
  std::set<int> wire;
  for (JobPhase p : {JobPhase::kSubmitted, JobPhase::kLoadingScene, JobPhase::kBootstrapping,
                     JobPhase::kRendering, JobPhase::kFinishing, JobPhase::kDone,
                     JobPhase::kFailed, JobPhase::kCancelled}) {
    const v1::JobPhase m = toProto(p);
    EXPECT_NE(m, v1::PHASE_UNSPECIFIED) << jobPhaseName(p);
    EXPECT_TRUE(wire.insert(int(m)).second) << jobPhaseName(p) << " shares its wire value";
    EXPECT_EQ(fromProto(m), p) << jobPhaseName(p);
  }
  EXPECT_EQ(fromProto(v1::PHASE_UNSPECIFIED), JobPhase::kSubmitted);
  EXPECT_EQ(fromProto(static_cast<v1::JobPhase>(99)), JobPhase::kSubmitted);
}

}  // namespace
}  // namespace farm
