#include "coordinator/store_records.h"

#include <gtest/gtest.h>

#include <fstream>

#include "proto/convert.h"
#include "proto/coordinator_store.pb.h"
#include "proto/zstd_frame.h"

namespace farm {
namespace {

ChainFlush entry(uint32_t chain, uint32_t index) {
  ChainFlush f;
  f.chainIndex = chain;
  f.flushIndex = index;
  f.mutations = 1000 + chain;
  f.rejected.nan = 1;
  f.rejected.infinite = 2;
  f.rejected.negative = 3;
  f.rays = 5000 + chain;
  f.state = "state of chain " + std::to_string(chain);
  f.finished = chain == 1;
  f.tallies = {{"small step", 40, 30}, {"large step", 8, 2}};
  f.largeSteps.count = 8;
  f.largeSteps.sum = 2.5;
  f.largeSteps.sumSquares = 1.25;
  return f;
}

void expectSameEntry(const ChainFlush& a, const ChainFlush& b) {
  EXPECT_EQ(a.chainIndex, b.chainIndex);
  EXPECT_EQ(a.flushIndex, b.flushIndex);
  EXPECT_EQ(a.mutations, b.mutations);
  EXPECT_EQ(a.rejected.nan, b.rejected.nan);
  EXPECT_EQ(a.rejected.infinite, b.rejected.infinite);
  EXPECT_EQ(a.rejected.negative, b.rejected.negative);
  EXPECT_EQ(a.rays, b.rays);
  EXPECT_EQ(a.state, b.state);
  EXPECT_EQ(a.finished, b.finished);
  ASSERT_EQ(a.tallies.size(), b.tallies.size());
  for (size_t i = 0; i < a.tallies.size(); ++i) {
    EXPECT_EQ(a.tallies[i].name, b.tallies[i].name);
    EXPECT_EQ(a.tallies[i].proposed, b.tallies[i].proposed);
    EXPECT_EQ(a.tallies[i].accepted, b.tallies[i].accepted);
  }
  EXPECT_EQ(a.largeSteps.count, b.largeSteps.count);
  EXPECT_EQ(a.largeSteps.sum, b.largeSteps.sum);
  EXPECT_EQ(a.largeSteps.sumSquares, b.largeSteps.sumSquares);
}

FlushBatch batchOf(std::vector<ChainFlush> entries) {
  FlushBatch batch;
  batch.film.width = 3;
  batch.film.height = 2;
  for (int i = 0; i < 18; ++i) batch.film.splats.push_back(i % 4 == 0 ? 0.0f : 0.25f * float(i));
  batch.entries = std::move(entries);
  batch.epochs.assign(batch.entries.size(), 7);
  return batch;
}

TEST(StoreRecords, ABatchComesBackAsItWasRecorded) {
  for (size_t n : {1, 3}) {
    std::vector<ChainFlush> entries;
    for (uint32_t c = 0; c < n; ++c) entries.push_back(entry(c, 4 + c));
    const FlushBatch batch = batchOf(entries);
    FlushBatch back;
    std::string error;
    ASSERT_TRUE(store::decodeRecord(store::encodeBatch(batch, nullptr), &back, &error)) << error;
    EXPECT_EQ(back.film.width, 3);
    EXPECT_EQ(back.film.height, 2);
    EXPECT_EQ(back.film.splats, batch.film.splats);
    ASSERT_EQ(back.entries.size(), n);
    EXPECT_EQ(back.epochs, std::vector<uint64_t>(n, 0)) << "epochs are not recorded";
    for (size_t i = 0; i < n; ++i) {
      expectSameEntry(back.entries[i], batch.entries[i]);
      EXPECT_TRUE(back.entries[i].splats.empty());
    }
  }
}

// A flush as coordinators of schema version 3 and before recorded it (FlushRecord's older forms).
void writeOlderEntry(const ChainFlush& flush, store::v1::FlushRecord* r) {
  r->set_chain_index(flush.chainIndex);
  r->set_flush_index(flush.flushIndex);
  r->set_mutations(flush.mutations);
  r->set_rejected_nan(flush.rejected.nan);
  r->set_rejected_infinite(flush.rejected.infinite);
  r->set_rejected_negative(flush.rejected.negative);
  r->set_rays(flush.rays);
  r->set_state(flush.state);
  for (const MutationTally& t : flush.tallies) toProto(t, r->add_tallies());
  toProto(flush.largeSteps, r->mutable_large_steps());
  r->set_finished(flush.finished);
}

// A log left behind by a coordinator of schema version 3 still resumes: its single flushes (in
// the record's own fields) read as batches of one, its batches (entries without a film) as they
// were.
TEST(StoreRecords, RecordsOfTheOlderFormsReadAsTheyWere) {
  const FlushBatch batch = batchOf({entry(2, 9), entry(3, 4)});
  const EncodedSplats splats = encodeSplats(batch.film.splats);
  store::v1::FlushRecord film;
  film.set_width(3);
  film.set_height(2);
  film.set_splats(splats.bytes);
  film.set_sparse(splats.sparse);
  film.set_compressed(splats.compressed);
  film.set_raw_splat_bytes(splats.rawBytes);

  store::v1::FlushRecord single = film;
  writeOlderEntry(batch.entries[0], &single);
  FlushBatch back;
  std::string error;
  ASSERT_TRUE(store::decodeRecord(single.SerializeAsString(), &back, &error)) << error;
  EXPECT_EQ(back.film.splats, batch.film.splats);
  ASSERT_EQ(back.entries.size(), 1u);
  expectSameEntry(back.entries[0], batch.entries[0]);

  store::v1::FlushRecord older = film;
  for (const ChainFlush& e : batch.entries) writeOlderEntry(e, older.add_entries());
  back = FlushBatch();
  ASSERT_TRUE(store::decodeRecord(older.SerializeAsString(), &back, &error)) << error;
  EXPECT_EQ(back.film.splats, batch.film.splats);
  ASSERT_EQ(back.entries.size(), 2u);
  for (size_t i = 0; i < 2; ++i) expectSameEntry(back.entries[i], batch.entries[i]);
}

TEST(StoreRecords, ARecordThatDoesNotDecodeSaysSo) {
  FlushBatch back;
  std::string error;
  EXPECT_FALSE(store::decodeRecord("not a record", &back, &error));
  EXPECT_NE(error.find("unreadable flush record"), std::string::npos) << error;
  // A film whose bytes do not match its size names the flush.
  FlushBatch batch = batchOf({entry(5, 1)});
  store::v1::FlushRecord r;
  ASSERT_TRUE(r.ParseFromString(store::encodeBatch(batch, nullptr)));
  r.set_width(4);
  error.clear();
  EXPECT_FALSE(store::decodeRecord(r.SerializeAsString(), &back, &error));
  EXPECT_NE(error.find("flush 1 of chain 5"), std::string::npos) << error;
}

// Two groups of a 1x2 film (6 values), fed so that each film holds values a float cannot hold
// exactly once summed: the image in double, each group in float.
SplatAggregator twoGroupSums() {
  SplatAggregator sums(1, 2, std::vector<uint32_t>{0, 1});
  for (uint32_t chain = 0; chain < 2; ++chain) {
    ChainFlush f;
    f.chainIndex = chain;
    f.mutations = 10 + chain;
    f.width = 1;
    f.height = 2;
    f.splats = {16777216.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f};
    EXPECT_EQ(sums.add(f), FlushOutcome::kAccepted);
    f.flushIndex = 1;
    f.splats = {1.0f, 0.5f, 0.25f, float(chain), 0.0f, 7.0f};
    EXPECT_EQ(sums.add(f), FlushOutcome::kAccepted);
  }
  return sums;
}

// A checkpoint's films come back as the aggregator held them: the image's in double, each
// group's in float (layout 1), and the aggregator they restore goes on from there.
TEST(StoreRecords, ACheckpointsFilmsComeBackAsTheyWereHeld) {
  const SplatAggregator sums = twoGroupSums();
  const std::string dir = ::testing::TempDir();
  std::ofstream(dir + "/films.sums", std::ios::binary) << store::encodeFilms(sums);
  SplatAggregator::Snapshot counts = sums.snapshot(false);
  counts.priorWork = 5;  // as if an allocation pilot's 5 samples were among the 42
  const std::string record = store::encodeCheckpoint(counts, {}, "films.sums");
  SplatAggregator::Snapshot back;
  std::vector<ChainScheduler::ChainSnapshot> chains;
  std::string file, error;
  ASSERT_TRUE(store::decodeCheckpoint(record, 6, 2, dir, &back, &chains, &file, &error)) << error;
  EXPECT_EQ(file, "films.sums");
  EXPECT_EQ(back.sums, sums.sums());
  EXPECT_EQ(back.sums[0], 2 * (16777216.0 + 1.0)) << "the image keeps what a float would lose";
  ASSERT_EQ(back.groupSums.size(), 2u);
  for (uint32_t g = 0; g < 2; ++g) EXPECT_EQ(back.groupSums[g], sums.groupSums(g));
  EXPECT_EQ(back.groupWork, (std::vector<int64_t>{20, 22}));
  back.nextFlush = {2, 2};
  const SplatAggregator restored(1, 2, {0, 1}, std::move(back));
  EXPECT_EQ(restored.sums(), sums.sums());
  EXPECT_EQ(restored.groupSums(1), sums.groupSums(1));
  EXPECT_EQ(restored.workDone(), 42);
  EXPECT_EQ(restored.priorWork(), 5) << "the pilot's share of the work";

  // Films that do not fit the job (a group's frame missing, or a film of another size) say so.
  for (const auto& [values, groups] : {std::pair<size_t, uint32_t>{6, 3}, {9, 2}}) {
    SplatAggregator::Snapshot wrong;
    chains.clear();
    EXPECT_FALSE(
        store::decodeCheckpoint(record, values, groups, dir, &wrong, &chains, &file, &error));
    EXPECT_NE(error.find("missing, corrupt or of another film size"), std::string::npos) << error;
  }
}

// A checkpoint written before layout 1 (every group's film in double, one frame) still resumes:
// the groups are summed into the image and kept as float.
TEST(StoreRecords, CheckpointsOfTheOlderLayoutReadAsTheirSum) {
  const std::vector<double> films = {1e8 + 1, 2, 3, 4, 5, 6, 1, 0.5, 0.25, 0, 0, 7};
  store::v1::CheckpointRecord r;
  r.set_sums_zstd(zstdCompress(films.data(), films.size() * sizeof(double)));
  r.add_group_work(5);
  r.add_group_work(6);
  SplatAggregator::Snapshot back;
  std::vector<ChainScheduler::ChainSnapshot> chains;
  std::string file, error;
  ASSERT_TRUE(
      store::decodeCheckpoint(r.SerializeAsString(), 6, 2, "", &back, &chains, &file, &error))
      << error;
  EXPECT_EQ(back.sums, (std::vector<double>{1e8 + 2, 2.5, 3.25, 4, 5, 13}));
  ASSERT_EQ(back.groupSums.size(), 2u);
  EXPECT_EQ(back.groupSums[0], (std::vector<float>{1e8f, 2, 3, 4, 5, 6}));
  EXPECT_EQ(back.groupSums[1], (std::vector<float>{1, 0.5f, 0.25f, 0, 0, 7}));

  // One group: the image alone, no group film.
  r.set_sums_zstd(zstdCompress(films.data(), 6 * sizeof(double)));
  r.clear_group_work();
  back = SplatAggregator::Snapshot();
  ASSERT_TRUE(
      store::decodeCheckpoint(r.SerializeAsString(), 6, 1, "", &back, &chains, &file, &error))
      << error;
  EXPECT_EQ(back.sums, std::vector<double>(films.begin(), films.begin() + 6));
  EXPECT_TRUE(back.groupSums.empty());

  r.set_sums_layout(7);
  EXPECT_FALSE(
      store::decodeCheckpoint(r.SerializeAsString(), 6, 1, "", &back, &chains, &file, &error));
  EXPECT_NE(error.find("layout 7"), std::string::npos) << error;
}

}  // namespace
}  // namespace farm

namespace farm {
namespace {

// A plan whose bdpt samples a pilot placed comes back with its allocation, in the planned
// settings and in every chain (a restarted coordinator resumes them as they were leased); the
// record holds the allocation's bytes once, not once per chain.
TEST(StoreRecords, APlansPixelAllocationComesBack) {
  constexpr int kCells = 64;
  std::vector<float> density(kCells * kCells);
  for (size_t i = 0; i < density.size(); ++i) density[i] = 1.0f + float(i % 7);
  auto allocation = std::make_shared<const PixelAllocation>(
      kCells, kCells, 1, density, std::vector<uint8_t>(density.size(), 1));
  JobPlan plan;
  plan.width = kCells;
  plan.height = kCells;
  RenderSettings settings;
  settings.algorithm = Algorithm::Bidirectional;
  settings.pixelAllocation = allocation;
  plan.plannedSettings = settings;
  for (uint32_t c = 0; c < 8; ++c) {
    ChainSpec spec;
    spec.chainIndex = c;
    spec.algorithm = Algorithm::Bidirectional;
    spec.flushInterval = 64;
    spec.pixelAllocation = allocation;
    plan.chains.push_back(spec);
  }
  const std::string record = store::encodePlan(plan);
  EXPECT_LT(record.size(), 2 * allocation->encode().size()) << "the allocation is stored per chain";
  JobPlan back;
  std::string error;
  ASSERT_TRUE(store::decodePlan(record, &back, &error)) << error;
  ASSERT_TRUE(back.plannedSettings && back.plannedSettings->pixelAllocation);
  EXPECT_EQ(back.plannedSettings->pixelAllocation->encode(), allocation->encode());
  ASSERT_EQ(back.chains.size(), 8u);
  for (const ChainSpec& c : back.chains) {
    ASSERT_TRUE(c.pixelAllocation);
    EXPECT_EQ(c.pixelAllocation.get(), back.plannedSettings->pixelAllocation.get());
  }

  // A record of protocol 7 held the bytes in every chain: its chains come back sharing one.
  store::v1::PlanRecord old;
  ASSERT_TRUE(old.ParseFromString(record));
  for (v1::ChainSpec& c : *old.mutable_chains()) {
    c.clear_pixel_allocation_hash();
    c.set_pixel_allocation(allocation->encode());
  }
  JobPlan older;
  ASSERT_TRUE(store::decodePlan(old.SerializeAsString(), &older, &error)) << error;
  ASSERT_EQ(older.chains.size(), 8u);
  for (const ChainSpec& c : older.chains) {
    ASSERT_TRUE(c.pixelAllocation);
    EXPECT_EQ(c.pixelAllocation.get(), older.plannedSettings->pixelAllocation.get());
  }

  // Chains whose allocation the planned settings do not hold keep its bytes in their record.
  plan.plannedSettings->pixelAllocation = nullptr;
  JobPlan apart;
  ASSERT_TRUE(store::decodePlan(store::encodePlan(plan), &apart, &error)) << error;
  ASSERT_EQ(apart.chains.size(), 8u);
  for (const ChainSpec& c : apart.chains) {
    ASSERT_TRUE(c.pixelAllocation);
    EXPECT_EQ(c.pixelAllocation->encode(), allocation->encode());
  }
  // A record whose chains name an allocation it does not hold is unreadable, and says so.
  store::v1::PlanRecord broken;
  ASSERT_TRUE(broken.ParseFromString(record));
  broken.mutable_planned_settings()->clear_pixel_allocation();
  JobPlan unreadable;
  EXPECT_FALSE(store::decodePlan(broken.SerializeAsString(), &unreadable, &error));
  EXPECT_NE(error.find("did not come with it"), std::string::npos) << error;
}

}  // namespace
}  // namespace farm
