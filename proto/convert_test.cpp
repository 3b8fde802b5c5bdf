// proto/convert.h: the job phase, the one enum the coordinator, the store and the clients all
// report, crosses the wire and comes back as itself (what a newer or broken peer sends that this
// build does not know reads as submitted); so do a job's progress, field by field, and the
// settings and work units of Kelemen's combined large steps.
#include "proto/convert.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <set>
#include <string>

#include "proto/sha256.h"

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

// Every field of a job's progress reaches the wire (a field the message has but toProto leaves
// at its default fails here) and comes back (one fromProto drops changes the second message).
TEST(Convert, EveryFieldOfAJobsProgressCrossesTheWireAndBack) {
  JobProgress p;
  p.jobId = "job-1";
  p.name = "box";
  p.error = "none yet";
  p.phase = JobPhase::kRendering;
  p.fraction = 0.25;
  p.samplesPerSecond = 1e6;
  p.elapsedSeconds = 3;
  p.etaSeconds = 9;
  p.workDone = 100;
  p.pilotWork = 30;
  p.plannedWork = 400;
  p.rejected.nan = 1;
  p.rejected.infinite = 2;
  p.rejected.negative = 3;
  p.rays = 5000;
  p.tallies = {{"large step", 10, 4}};
  p.warnings = {"left out a triangle"};
  p.renderPlan = {"pt: no caustics"};
  p.setAside = {"worker-2: bad flushes"};
  p.raysPerSecond = 2e6;
  p.normalization = 0.5;
  p.normalizationStdError = 0.01;
  p.bootstrapCandidates = 4096;
  p.largeSteps = 30;
  p.abandonedConnections = 2;
  p.loadSeconds = 0.1;
  p.bootstrapSeconds = 0.2;
  p.renderSeconds = 2.5;
  p.chainsTotal = 64;
  p.chainsFinished = 8;
  p.chainsLeased = 4;
  p.activeWorkers = 2;
  p.hasReference = true;
  p.errorSeries = {{1.5, 50, 0.1, 0.01, 0.02}};
  p.errorSeriesTotal = 7;
  p.width = 32;
  p.height = 24;
  p.settings.algorithm = Algorithm::MMLT;

  v1::JobProgress m;
  toProto(p, &m);
  const google::protobuf::Reflection* reflection = m.GetReflection();
  const google::protobuf::Descriptor* descriptor = m.GetDescriptor();
  for (int i = 0; i < descriptor->field_count(); ++i) {
    const google::protobuf::FieldDescriptor* field = descriptor->field(i);
    const bool set =
        field->is_repeated() ? reflection->FieldSize(m, field) > 0 : reflection->HasField(m, field);
    EXPECT_TRUE(set) << field->name() << " is left at its default";
  }
  JobProgress back;
  fromProto(m, &back);
  v1::JobProgress again;
  toProto(back, &again);
  EXPECT_EQ(again.SerializeAsString(), m.SerializeAsString())
      << "was:\n"
      << m.DebugString() << "came back as:\n"
      << again.DebugString();
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

namespace farm {
namespace {

// A pixel allocation crosses the wire whole in a job's settings (and so into the store, which
// keeps them as this message); a pt or bdpt work unit names it by hash and takes it from what
// came beside it. A malformed one, bytes that are not the hash's, a hash nothing came with and an
// allocation on a chain that cannot take it are refused with the reason.
TEST(Convert, PixelAllocationCrossesTheWire) {
  auto allocation = std::make_shared<const PixelAllocation>(3, 2, 2, std::vector<float>{1, 2},
                                                            std::vector<uint8_t>{0, 1});
  RenderSettings settings;
  settings.algorithm = Algorithm::Bidirectional;
  settings.pixelAllocation = allocation;
  RenderSettings back;
  std::string error;
  ASSERT_TRUE(fromProto(toProto(settings), &back, &error)) << error;
  ASSERT_TRUE(back.pixelAllocation);
  EXPECT_EQ(back.pixelAllocation->encode(), allocation->encode());
  EXPECT_TRUE(toProto(settings, WithAllocation::kLeftOut).pixel_allocation().empty());

  ChainSpec spec;
  spec.algorithm = Algorithm::PathTracing;
  spec.flushInterval = 100;
  spec.pixelAllocation = allocation;
  const v1::ChainSpec unit = toProto(spec);
  EXPECT_TRUE(unit.pixel_allocation().empty()) << "the bytes travel once per job, not per chain";
  EXPECT_EQ(unit.pixel_allocation_hash(), sha256Hex(allocation->encode()));
  std::shared_ptr<const PixelAllocation> arrived;
  ASSERT_TRUE(
      decodePixelAllocation(allocation->encode(), unit.pixel_allocation_hash(), &arrived, &error))
      << error;
  const AllocationLookup lookup = [&](const std::string& hash) {
    return hash == unit.pixel_allocation_hash() ? arrived : nullptr;
  };
  ChainSpec chain;
  ASSERT_TRUE(fromProto(unit, &chain, &error, lookup)) << error;
  ASSERT_TRUE(chain.pixelAllocation);
  EXPECT_EQ(chain.pixelAllocation->density(), allocation->density());

  EXPECT_FALSE(fromProto(unit, &chain, &error));
  EXPECT_NE(error.find("did not come with it"), std::string::npos) << error;
  std::string truncated = allocation->encode();
  truncated.pop_back();
  EXPECT_FALSE(decodePixelAllocation(truncated, unit.pixel_allocation_hash(), &arrived, &error));
  EXPECT_NE(error.find("pixel allocation"), std::string::npos) << error;
  EXPECT_FALSE(decodePixelAllocation(truncated, sha256Hex(truncated), &arrived, &error));
  EXPECT_NE(error.find("pixel allocation"), std::string::npos) << error;
  v1::RenderSettings badSettings = toProto(settings);
  badSettings.set_pixel_allocation("not one");
  EXPECT_FALSE(fromProto(badSettings, &back, &error));
  EXPECT_NE(error.find("pixel allocation"), std::string::npos) << error;

  // A plan record of protocol 7 kept the bytes in each chain: still resumed.
  v1::ChainSpec old = unit;
  old.clear_pixel_allocation_hash();
  old.set_pixel_allocation(allocation->encode());
  ASSERT_TRUE(fromProto(old, &chain, &error)) << error;
  ASSERT_TRUE(chain.pixelAllocation);
  EXPECT_EQ(chain.pixelAllocation->encode(), allocation->encode());
  old.mutable_pixel_allocation()->pop_back();
  EXPECT_FALSE(fromProto(old, &chain, &error));
  EXPECT_NE(error.find("pixel allocation"), std::string::npos) << error;

  spec.algorithm = Algorithm::PSSMLT;
  EXPECT_FALSE(fromProto(toProto(spec), &chain, &error, lookup));
  EXPECT_NE(error.find("only pt and bdpt"), std::string::npos) << error;
}

// The hash a work unit names is its allocation's, also when the thread asked about another last
// (the memo is of one allocation, which must not answer for the next).
TEST(Convert, PixelAllocationHashIsEachAllocations) {
  auto a = std::make_shared<const PixelAllocation>(3, 2, 2, std::vector<float>{1, 2},
                                                   std::vector<uint8_t>{0, 1});
  auto b = std::make_shared<const PixelAllocation>(3, 2, 2, std::vector<float>{2, 1},
                                                   std::vector<uint8_t>{0, 1});
  EXPECT_EQ(pixelAllocationHash(a), sha256Hex(a->encode()));
  EXPECT_EQ(pixelAllocationHash(b), sha256Hex(b->encode()));
  EXPECT_EQ(pixelAllocationHash(a), sha256Hex(a->encode()));
  for (int i = 0; i < 3; ++i) {  // freed and made again, possibly at the same address
    a.reset();
    a = std::make_shared<const PixelAllocation>(3, 2, 2, std::vector<float>{1, float(3 + i)},
                                                std::vector<uint8_t>{0, 1});
    EXPECT_EQ(pixelAllocationHash(a), sha256Hex(a->encode()));
  }
  EXPECT_EQ(pixelAllocationHash(nullptr), "");
}

}  // namespace
}  // namespace farm
