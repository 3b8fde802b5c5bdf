// A worker's summed upload of several chains' flushes (issue 8, part 4): the coordinator takes
// a batch whole or not at all and counts every chain's flush exactly once, in memory and across
// a restart; the worker's batcher sums the chains of one job, sends when all have flushed or
// the window passes, sends again what the coordinator held back, and keeps jobs apart.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "coordinator/coordinator.h"
#include "coordinator/coordinator_test_support.h"
#include "tests/test_support.h"
#include "worker/flush_batcher.h"

namespace farm {
namespace {

using std::chrono::milliseconds;

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

// 32x32 at 32 samples per pixel over two chains of one error group (a batch holds one group's
// chains): four flushes of 4096 samples each.
RenderSettings twoChains() {
  RenderSettings s;
  s.algorithm = Algorithm::PathTracing;
  s.width = 32;
  s.height = 32;
  s.samplesPerPixel = 32;
  s.numChains = 2;
  s.errorGroups = 1;
  s.seed = 3;
  return s;
}

std::string submitAndWait(Coordinator& coordinator) {
  JobSpec spec;
  spec.settings = twoChains();
  spec.scenePath = kScene;
  return submitAndWaitForRendering(coordinator, spec);
}

// Every flush of the two leased chains, by chain and index.
std::vector<std::vector<ChainFlush>> renderFlushes(Coordinator& coordinator,
                                                   const std::vector<WorkerLease>& leases) {
  std::vector<std::vector<ChainFlush>> flushes(leases.size());
  for (const WorkerLease& lease : leases) {
    coordinator.renderJob(lease.jobId)->runChain(lease.lease.spec, [&](ChainFlush&& f) {
      flushes[f.chainIndex].push_back(std::move(f));
      return true;
    });
  }
  return flushes;
}

// The given flushes as one batch: their films summed, their counts as entries.
FlushBatch batchOf(const std::vector<const ChainFlush*>& flushes, uint64_t epoch) {
  FlushBatch batch;
  batch.film.width = flushes.front()->width;
  batch.film.height = flushes.front()->height;
  std::vector<double> sum(flushes.front()->splats.size(), 0.0);
  for (const ChainFlush* f : flushes) {
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += f->splats[i];
    ChainFlush entry = *f;
    entry.splats.clear();
    batch.entries.push_back(std::move(entry));
    batch.epochs.push_back(epoch);
  }
  batch.film.splats.assign(sum.begin(), sum.end());
  return batch;
}

std::vector<FlushAck::Result> results(const std::vector<FlushAck>& acks) {
  std::vector<FlushAck::Result> r;
  for (const FlushAck& a : acks) r.push_back(a.result);
  return r;
}

int64_t workDone(Coordinator& coordinator, const std::string& job) {
  JobProgress p;
  EXPECT_TRUE(coordinator.progress(job, 0, &p).isOk());
  return p.workDone;
}

double worstRelativeDifference(const Image& a, const Image& b) {
  EXPECT_EQ(a.rgb.size(), b.rgb.size());
  double worst = 0;
  for (size_t i = 0; i < std::min(a.rgb.size(), b.rgb.size()); ++i) {
    if (std::abs(b.rgb[i]) > 1e-3) {
      worst = std::max(worst, double(std::abs(a.rgb[i] - b.rgb[i]) / std::abs(b.rgb[i])));
    }
  }
  return worst;
}

Image finish(Coordinator& coordinator, const std::string& job) {
  JobPhase phase;
  coordinator.waitForEnd(job, std::chrono::seconds(30), &phase);
  EXPECT_EQ(phase, JobPhase::kDone);
  Image image;
  EXPECT_TRUE(coordinator.finalImage(job, &image, nullptr).isOk());
  return image;
}

class BatchedFlushes : public ::testing::TestWithParam<bool> {};  // durable, with a restart

TEST_P(BatchedFlushes, CountOnceWholeOrNotAtAll) {
  testing::ScratchDir scratch("batches");
  const bool durable = GetParam();
  using R = FlushAck::Result;

  // The same job with every flush on its own: the image the batches must give.
  Image expected;
  {
    CoordinatorOptions options;
    options.dataDir = scratch / "straight";
    Coordinator coordinator(options);
    const std::string job = submitAndWait(coordinator);
    const std::string worker = registerTestWorker(coordinator, 2);
    std::vector<WorkerLease> leases;
    ASSERT_TRUE(coordinator.leaseChains(worker, 2, &leases).isOk());
    for (auto& chain : renderFlushes(coordinator, leases)) {
      for (ChainFlush& f : chain) {
        FlushAck ack;
        ASSERT_TRUE(
            coordinator.acceptFlush(worker, job, leases[0].lease.epoch, std::move(f), &ack).isOk());
      }
    }
    expected = finish(coordinator, job);
  }

  CoordinatorOptions options;
  options.dataDir = scratch / "batched";
  options.durable = durable;
  options.leaseSeconds = 60;
  auto coordinator = std::make_unique<Coordinator>(options);
  const std::string job = submitAndWait(*coordinator);
  std::string worker = registerTestWorker(*coordinator, 2);
  std::vector<WorkerLease> leases;
  ASSERT_TRUE(coordinator->leaseChains(worker, 2, &leases).isOk());
  ASSERT_EQ(leases.size(), 2u);
  const uint64_t epoch = leases[0].lease.epoch;
  const auto flushes = renderFlushes(*coordinator, leases);
  ASSERT_EQ(flushes[0].size(), 4u);
  ASSERT_EQ(flushes[1].size(), 4u);
  auto accept = [&](FlushBatch batch, std::vector<FlushAck>* acks) {
    return coordinator->acceptBatch(worker, job, std::move(batch), acks);
  };

  // Flush 0 of both chains in one: both count, once.
  std::vector<FlushAck> acks;
  ASSERT_TRUE(accept(batchOf({&flushes[0][0], &flushes[1][0]}, epoch), &acks).isOk());
  EXPECT_EQ(results(acks), (std::vector<R>{R::kAccepted, R::kAccepted}));
  EXPECT_EQ(workDone(*coordinator, job), 2 * 4096);
  // The same batch again (its answer was lost): duplicates, nothing more counts.
  ASSERT_TRUE(accept(batchOf({&flushes[0][0], &flushes[1][0]}, epoch), &acks).isOk());
  EXPECT_EQ(results(acks), (std::vector<R>{R::kDuplicate, R::kDuplicate}));
  EXPECT_EQ(workDone(*coordinator, job), 2 * 4096);
  // A new flush beside a duplicate: the film cannot be split, so nothing counts; the new one
  // is to be sent again on its own.
  ASSERT_TRUE(accept(batchOf({&flushes[0][1], &flushes[1][0]}, epoch), &acks).isOk());
  EXPECT_EQ(results(acks), (std::vector<R>{R::kResend, R::kDuplicate}));
  EXPECT_EQ(workDone(*coordinator, job), 2 * 4096);
  // A flush with a negative count beside a sound one: the first refused with its reason.
  ChainFlush bad = flushes[1][1];
  bad.mutations = -1;
  ASSERT_TRUE(accept(batchOf({&flushes[0][1], &bad}, epoch), &acks).isOk());
  EXPECT_EQ(results(acks), (std::vector<R>{R::kResend, R::kRefused}));
  EXPECT_NE(acks[1].reason.find("negative"), std::string::npos) << acks[1].reason;
  // Out of order: flush 3 of chain 1 before its 1 and 2.
  ASSERT_TRUE(accept(batchOf({&flushes[0][1], &flushes[1][3]}, epoch), &acks).isOk());
  EXPECT_EQ(results(acks), (std::vector<R>{R::kResend, R::kRefused}));
  EXPECT_EQ(workDone(*coordinator, job), 2 * 4096);
  // Malformed as a whole: two flushes of one chain, a film of another size.
  EXPECT_EQ(accept(batchOf({&flushes[0][1], &flushes[0][2]}, epoch), &acks).code(),
            StatusCode::kInvalidArgument);
  FlushBatch wrong = batchOf({&flushes[0][1], &flushes[1][1]}, epoch);
  wrong.film.splats.pop_back();
  EXPECT_EQ(accept(std::move(wrong), &acks).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(workDone(*coordinator, job), 2 * 4096);
  // Flush 1 of both, then the job's coordinator dies (durable: it comes back from its log).
  ASSERT_TRUE(accept(batchOf({&flushes[0][1], &flushes[1][1]}, epoch), &acks).isOk());
  EXPECT_EQ(results(acks), (std::vector<R>{R::kAccepted, R::kAccepted}));
  EXPECT_EQ(workDone(*coordinator, job), 4 * 4096);
  uint64_t nextEpoch = epoch;
  if (durable) {
    coordinator.reset();
    coordinator = std::make_unique<Coordinator>(options);
    EXPECT_EQ(workDone(*coordinator, job), 4 * 4096) << "the batches replayed from the log";
    worker = registerTestWorker(*coordinator, 2);
    std::vector<WorkerLease> again;
    ASSERT_TRUE(coordinator->leaseChains(worker, 2, &again).isOk());
    ASSERT_EQ(again.size(), 2u);
    for (const WorkerLease& lease : again) {
      EXPECT_EQ(lease.lease.spec.resumeFlushIndex, 2u) << "chain " << lease.lease.spec.chainIndex;
      EXPECT_EQ(lease.lease.spec.resumeMutations, 2 * 4096);
    }
    nextEpoch = again[0].lease.epoch;
    ASSERT_TRUE(accept(batchOf({&flushes[0][1], &flushes[1][1]}, nextEpoch), &acks).isOk());
    EXPECT_EQ(results(acks), (std::vector<R>{R::kDuplicate, R::kDuplicate}));
  }
  // The rest, in batches; the last ones end both chains, and the job.
  for (size_t k = 2; k < 4; ++k) {
    ASSERT_TRUE(accept(batchOf({&flushes[1][k], &flushes[0][k]}, nextEpoch), &acks).isOk());
    EXPECT_EQ(results(acks), (std::vector<R>{R::kAccepted, R::kAccepted})) << "flushes " << k;
  }
  EXPECT_EQ(workDone(*coordinator, job), 8 * 4096);
  EXPECT_LT(worstRelativeDifference(finish(*coordinator, job), expected), 1e-5);
  // After the end a batch is discarded and its chains told to stop.
  ASSERT_TRUE(accept(batchOf({&flushes[0][3], &flushes[1][3]}, nextEpoch), &acks).isOk());
  EXPECT_EQ(results(acks), (std::vector<R>{R::kDiscarded, R::kDiscarded}));
  EXPECT_TRUE(acks[0].stop);
}

// Each error group is summed apart (its film is one of the groups whose spread estimates the
// error), so a batch of two groups' chains cannot be taken: it is refused whole, nothing counts.
TEST(BatchedFlushes, ABatchOfTwoErrorGroupsIsRefused) {
  CoordinatorOptions options;
  testing::ScratchDir scratch("batch-groups");
  options.dataDir = scratch.path();
  Coordinator coordinator(options);
  JobSpec spec;
  spec.settings = twoChains();
  spec.settings.errorGroups = 2;
  spec.scenePath = kScene;
  std::string job;
  ASSERT_TRUE(coordinator.submit(spec, &job).isOk());
  for (int i = 0; i < 1200 && !coordinator.renderJob(job); ++i)
    std::this_thread::sleep_for(milliseconds(50));
  const std::string worker = registerTestWorker(coordinator, 2);
  std::vector<WorkerLease> leases;
  ASSERT_TRUE(coordinator.leaseChains(worker, 2, &leases).isOk());
  ASSERT_EQ(leases.size(), 2u);
  EXPECT_NE(leases[0].lease.spec.errorGroup, leases[1].lease.spec.errorGroup);
  const auto flushes = renderFlushes(coordinator, leases);
  std::vector<FlushAck> acks;
  const Status refused = coordinator.acceptBatch(
      worker, job, batchOf({&flushes[0][0], &flushes[1][0]}, leases[0].lease.epoch), &acks);
  EXPECT_EQ(refused.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(refused.message().find("error groups 0 and 1"), std::string::npos) << refused.message();
  EXPECT_EQ(workDone(coordinator, job), 0);
  // Each on its own counts.
  for (int c = 0; c < 2; ++c) {
    ASSERT_TRUE(
        coordinator
            .acceptBatch(worker, job, batchOf({&flushes[c][0]}, leases[0].lease.epoch), &acks)
            .isOk());
    EXPECT_EQ(acks[0].result, FlushAck::Result::kAccepted);
  }
  EXPECT_EQ(workDone(coordinator, job), 2 * 4096);
}

INSTANTIATE_TEST_SUITE_P(Store, BatchedFlushes, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "durable" : "in_memory"; });

// --- the worker's batcher, without a network ---

LeasedChain chainOf(const std::string& job, uint32_t index) {
  LeasedChain c;
  c.jobId = job;
  c.spec.chainIndex = index;
  return c;
}

ChainFlush flushOf(uint32_t chain, uint32_t index) {
  ChainFlush f;
  f.chainIndex = chain;
  f.flushIndex = index;
  f.width = 1;
  f.height = 1;
  f.splats = {1.0f, 2.0f, 3.0f};
  return f;
}

struct Recorder {
  std::mutex mutex;
  std::vector<std::vector<std::pair<std::string, uint32_t>>> batches;  // (job, chain) per item
  std::function<BatchAnswer(const BatchItem&, int attempt)> answer;
  std::map<uint32_t, int> attempts;

  std::vector<BatchAnswer> operator()(const std::vector<BatchItem*>& items) {
    std::lock_guard<std::mutex> lock(mutex);
    batches.emplace_back();
    std::vector<BatchAnswer> answers;
    for (const BatchItem* item : items) {
      batches.back().emplace_back(item->chain->jobId, item->flush.chainIndex);
      answers.push_back(answer(*item, attempts[item->flush.chainIndex]++));
    }
    return answers;
  }
};

BatchAnswer accepted() {
  BatchAnswer a;
  a.kind = BatchAnswer::Kind::kReceipt;
  a.receipt.accepted = true;
  return a;
}

TEST(FlushBatcher, SendsOneBatchOnceEveryChainOfTheJobHasFlushed) {
  Recorder recorder;
  recorder.answer = [](const BatchItem&, int) { return accepted(); };
  FlushBatcher batcher(60, [&](const std::vector<BatchItem*>& items) { return recorder(items); });
  const LeasedChain a = chainOf("job-a", 0), b = chainOf("job-a", 1), c = chainOf("job-a", 2);
  for (int i = 0; i < 3; ++i) batcher.chainStarted(FlushBatcher::key("job-a", 0));
  std::vector<std::thread> threads;
  std::atomic<int> answered{0};
  for (const LeasedChain* chain : {&a, &b, &c}) {
    threads.emplace_back([&, chain] {
      if (batcher.upload(*chain, flushOf(chain->spec.chainIndex, 0)).accepted) ++answered;
    });
    std::this_thread::sleep_for(milliseconds(50));
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(answered.load(), 3);
  ASSERT_EQ(recorder.batches.size(), 1u) << "a window of 60 s: only a full batch goes";
  EXPECT_EQ(recorder.batches[0].size(), 3u);
  EXPECT_EQ(batcher.stats().batches, 1);
  EXPECT_EQ(batcher.stats().flushes, 3);
}

TEST(FlushBatcher, ChainsOfTwoErrorGroupsGoInBatchesOfTheirOwn) {
  Recorder recorder;
  recorder.answer = [](const BatchItem&, int) { return accepted(); };
  FlushBatcher batcher(60, [&](const std::vector<BatchItem*>& items) { return recorder(items); });
  LeasedChain chains[4] = {chainOf("job-a", 0), chainOf("job-a", 1), chainOf("job-a", 2),
                           chainOf("job-a", 3)};
  chains[2].spec.errorGroup = chains[3].spec.errorGroup = 1;
  for (const LeasedChain& c : chains) batcher.chainStarted(FlushBatcher::key(c));
  std::vector<std::thread> threads;
  for (const LeasedChain& c : chains) {
    threads.emplace_back([&] { batcher.upload(c, flushOf(c.spec.chainIndex, 0)); });
  }
  for (std::thread& t : threads) t.join();
  ASSERT_EQ(recorder.batches.size(), 2u) << "one full batch a group, at once";
  for (const auto& batch : recorder.batches) {
    ASSERT_EQ(batch.size(), 2u);
    EXPECT_EQ(batch[0].second / 2, batch[1].second / 2) << "chains of one group together";
  }
}

TEST(FlushBatcher, ALoneFlushGoesWhenTheWindowEndsOrItsPeerEnds) {
  Recorder recorder;
  recorder.answer = [](const BatchItem&, int) { return accepted(); };
  FlushBatcher batcher(0.2, [&](const std::vector<BatchItem*>& items) { return recorder(items); });
  const LeasedChain a = chainOf("job-a", 0);
  batcher.chainStarted(FlushBatcher::key("job-a", 0));
  batcher.chainStarted(FlushBatcher::key("job-a", 0));  // its peer never flushes
  const auto start = std::chrono::steady_clock::now();
  EXPECT_TRUE(batcher.upload(a, flushOf(0, 0)).accepted);
  EXPECT_GE(std::chrono::steady_clock::now() - start, milliseconds(200));
  // With a window of a minute, the peer's end completes the batch.
  FlushBatcher patient(60, [&](const std::vector<BatchItem*>& items) { return recorder(items); });
  patient.chainStarted(FlushBatcher::key("job-a", 0));
  patient.chainStarted(FlushBatcher::key("job-a", 0));
  std::thread ender([&] {
    std::this_thread::sleep_for(milliseconds(100));
    patient.chainEnded(FlushBatcher::key("job-a", 0));
  });
  EXPECT_TRUE(patient.upload(a, flushOf(0, 1)).accepted);
  ender.join();
  EXPECT_EQ(recorder.batches.size(), 2u);
}

// A waiting chain's thread is idle: once a chain's interval is known, its flush waits for its
// peers at most kWaitShare of it, however long the window.
TEST(FlushBatcher, AFlushWaitsAtMostAShareOfItsChainsInterval) {
  Recorder recorder;
  recorder.answer = [](const BatchItem&, int) { return accepted(); };
  FlushBatcher batcher(5, [&](const std::vector<BatchItem*>& items) { return recorder(items); });
  const LeasedChain a = chainOf("job-a", 0), b = chainOf("job-a", 1);
  batcher.chainStarted(FlushBatcher::key("job-a", 0));
  batcher.chainStarted(FlushBatcher::key("job-a", 0));
  std::thread peer([&] { batcher.upload(b, flushOf(1, 0)); });
  EXPECT_TRUE(batcher.upload(a, flushOf(0, 0)).accepted);  // both: sent at once
  peer.join();
  std::this_thread::sleep_for(milliseconds(200));  // chain 0 renders its next flush
  const auto start = std::chrono::steady_clock::now();
  EXPECT_TRUE(batcher.upload(a, flushOf(0, 1)).accepted);  // chain 1 is still rendering
  const auto waited = std::chrono::steady_clock::now() - start;
  // 5% of 200 ms is 10 ms; a loaded machine may add scheduling delay, never the 5 s window.
  EXPECT_LT(waited, milliseconds(1000));
  ASSERT_EQ(recorder.batches.size(), 2u);
  EXPECT_EQ(recorder.batches[1].size(), 1u);
  // A chain that joins the job later waits by the job's interval too, not the window.
  const LeasedChain c = chainOf("job-a", 2);
  batcher.chainStarted(FlushBatcher::key("job-a", 0));
  const auto joined = std::chrono::steady_clock::now();
  EXPECT_TRUE(batcher.upload(c, flushOf(2, 0)).accepted);
  EXPECT_LT(std::chrono::steady_clock::now() - joined, milliseconds(1000));
}

TEST(FlushBatcher, SendsAgainWhatWasHeldBackAndFailsWhatCannotBeDelivered) {
  Recorder recorder;
  // Chain 0's first sending is held back by chain 1's refusal; it goes again alone.
  recorder.answer = [](const BatchItem& item, int attempt) {
    BatchAnswer a = accepted();
    if (item.flush.chainIndex == 0 && attempt == 0) a.kind = BatchAnswer::Kind::kResend;
    if (item.flush.chainIndex == 1) {
      a.kind = BatchAnswer::Kind::kError;
      a.error = "refused: negative count";
    }
    return a;
  };
  FlushBatcher batcher(60, [&](const std::vector<BatchItem*>& items) { return recorder(items); });
  const LeasedChain a = chainOf("job-a", 0), b = chainOf("job-a", 1);
  batcher.chainStarted(FlushBatcher::key("job-a", 0));
  batcher.chainStarted(FlushBatcher::key("job-a", 0));
  std::string error;
  std::thread other([&] {
    try {
      batcher.upload(b, flushOf(1, 0));
    } catch (const std::exception& e) {
      error = e.what();
    }
  });
  EXPECT_TRUE(batcher.upload(a, flushOf(0, 0)).accepted);
  other.join();
  EXPECT_EQ(error, "refused: negative count");
  ASSERT_EQ(recorder.batches.size(), 2u);
  EXPECT_EQ(recorder.batches[0].size(), 2u);
  EXPECT_EQ(recorder.batches[1], (std::vector<std::pair<std::string, uint32_t>>{{"job-a", 0}}));

  // A sending that throws fails every flush in it.
  FlushBatcher broken(0, [](const std::vector<BatchItem*>&) -> std::vector<BatchAnswer> {
    throw std::runtime_error("cannot deliver: coordinator gone");
  });
  broken.chainStarted(FlushBatcher::key("job-a", 0));
  EXPECT_THROW(broken.upload(a, flushOf(0, 0)), std::runtime_error);
}

TEST(FlushBatcher, KeepsJobsApart) {
  Recorder recorder;
  recorder.answer = [](const BatchItem&, int) { return accepted(); };
  FlushBatcher batcher(0.3, [&](const std::vector<BatchItem*>& items) { return recorder(items); });
  const LeasedChain a = chainOf("job-a", 0), b = chainOf("job-b", 0);
  for (const char* job : {"job-a", "job-a", "job-b", "job-b"}) batcher.chainStarted(job);
  std::thread other([&] { batcher.upload(b, flushOf(0, 0)); });
  batcher.upload(a, flushOf(0, 0));
  other.join();
  // Each job waits out the window for its second chain, alone.
  ASSERT_EQ(recorder.batches.size(), 2u);
  for (const auto& batch : recorder.batches) EXPECT_EQ(batch.size(), 1u);
  EXPECT_NE(recorder.batches[0][0].first, recorder.batches[1][0].first);
}

}  // namespace
}  // namespace farm
