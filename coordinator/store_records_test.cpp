#include "coordinator/store_records.h"

#include <gtest/gtest.h>

#include "proto/convert.h"
#include "proto/coordinator_store.pb.h"

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

}  // namespace
}  // namespace farm
