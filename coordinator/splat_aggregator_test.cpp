#include "coordinator/splat_aggregator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace farm {
namespace {

ChainFlush makeFlush(uint32_t chain, uint32_t index, float value, int w = 2, int h = 2) {
  ChainFlush f;
  f.chainIndex = chain;
  f.flushIndex = index;
  f.mutations = 100;
  f.width = w;
  f.height = h;
  f.splats.assign(size_t(w) * h * 3, value);
  return f;
}

TEST(SplatAggregator, AcceptsEachChainFlushExactlyOnce) {
  SplatAggregator sum(2, 2, 3);
  EXPECT_EQ(sum.add(makeFlush(0, 0, 1.0f)), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(makeFlush(0, 0, 1.0f)), FlushOutcome::kDuplicate);
  EXPECT_EQ(sum.add(makeFlush(1, 0, 2.0f)), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(makeFlush(0, 1, 4.0f)), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(makeFlush(0, 1, 4.0f)), FlushOutcome::kDuplicate);
  EXPECT_EQ(sum.add(makeFlush(1, 0, 2.0f)), FlushOutcome::kDuplicate);
  EXPECT_EQ(sum.workDone(), 300);
  EXPECT_EQ(sum.acceptedFlushes(), 3u);
  for (double v : sum.sums()) EXPECT_EQ(v, 7.0);
  EXPECT_EQ(sum.nextFlushIndex(0), 2u);
  EXPECT_EQ(sum.nextFlushIndex(1), 1u);
  EXPECT_EQ(sum.nextFlushIndex(2), 0u);
}

TEST(SplatAggregator, RejectsWhatDoesNotFitWithoutChangingTheSums) {
  SplatAggregator sum(2, 2, 2);
  std::string why;
  EXPECT_EQ(sum.add(makeFlush(2, 0, 1.0f), &why), FlushOutcome::kUnknownChain);
  EXPECT_NE(why.find("has no chain 2"), std::string::npos);
  EXPECT_EQ(sum.add(makeFlush(0, 1, 1.0f), &why), FlushOutcome::kOutOfOrder);
  EXPECT_EQ(sum.add(makeFlush(0, 0, 1.0f, 3, 2), &why), FlushOutcome::kWrongSize);
  ChainFlush nan = makeFlush(0, 0, 1.0f);
  nan.splats[5] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(sum.add(nan, &why), FlushOutcome::kBadValues);
  ChainFlush inf = makeFlush(0, 0, 1.0f);
  inf.splats[0] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(sum.add(inf, &why), FlushOutcome::kBadValues);
  ChainFlush negative = makeFlush(0, 0, 1.0f);
  negative.mutations = -1;
  EXPECT_EQ(sum.add(negative, &why), FlushOutcome::kBadValues);
  ChainFlush negativeCount = makeFlush(0, 0, 1.0f);
  negativeCount.rejected.nan = -3;
  EXPECT_EQ(sum.add(negativeCount, &why), FlushOutcome::kBadValues);
  EXPECT_EQ(sum.workDone(), 0);
  for (double v : sum.sums()) EXPECT_EQ(v, 0.0);
  // The rejected flushes did not consume flush index 0.
  EXPECT_EQ(sum.add(makeFlush(0, 0, 1.0f)), FlushOutcome::kAccepted);
}

// The chains' large steps (which refine Z) count once per accepted flush, survive a snapshot,
// and a flush whose sums no chain could make is refused whole.
TEST(SplatAggregator, LargeStepsCountOncePerAcceptedFlushAndSurviveASnapshot) {
  SplatAggregator sum(2, 2, 2);
  ChainFlush f = makeFlush(0, 0, 1.0f);
  f.largeSteps = {30, 6.0, 2.5};
  EXPECT_EQ(sum.add(f), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(f), FlushOutcome::kDuplicate);
  ChainFlush g = makeFlush(1, 0, 1.0f);
  g.largeSteps = {20, 4.0, 1.5};
  EXPECT_EQ(sum.add(g), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.largeSteps().count, 50);
  EXPECT_EQ(sum.largeSteps().sum, 10.0);
  EXPECT_EQ(sum.largeSteps().sumSquares, 4.0);
  SplatAggregator restored(2, 2, {0, 0}, sum.snapshot());
  EXPECT_EQ(restored.largeSteps().count, 50);
  EXPECT_EQ(restored.largeSteps().sum, 10.0);

  std::string why;
  for (LargeStepSums bad :
       {LargeStepSums{-1, 0, 0}, LargeStepSums{101, 1, 1}, LargeStepSums{5, -1, 1},
        LargeStepSums{5, 1, -1}, LargeStepSums{5, std::numeric_limits<double>::infinity(), 1},
        LargeStepSums{5, std::numeric_limits<double>::quiet_NaN(), 1}, LargeStepSums{0, 1, 1}}) {
    ChainFlush h = makeFlush(0, 1, 1.0f);
    h.largeSteps = bad;
    EXPECT_EQ(sum.add(h, &why), FlushOutcome::kBadValues) << bad.count << " " << bad.sum;
    EXPECT_NE(why.find("large steps"), std::string::npos) << why;
  }
  EXPECT_EQ(sum.largeSteps().count, 50) << "refused flushes count nothing";
}

// Acceptance tallies count once per accepted flush, like the splats; a malformed tally refuses
// the whole flush.
TEST(SplatAggregator, TalliesCountOncePerAcceptedFlush) {
  SplatAggregator sum(2, 2, 2);
  ChainFlush a = makeFlush(0, 0, 1.0f);
  a.tallies = {{"bidir", 10, 3}, {"lens", 5, 4}};
  ChainFlush b = makeFlush(1, 0, 1.0f);
  b.tallies = {{"lens", 7, 1}};
  EXPECT_EQ(sum.add(a), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(a), FlushOutcome::kDuplicate);
  EXPECT_EQ(sum.add(b), FlushOutcome::kAccepted);
  ASSERT_EQ(sum.tallies().size(), 2u);
  EXPECT_EQ(sum.tallies()[0].name, "bidir");
  EXPECT_EQ(sum.tallies()[0].proposed, 10);
  EXPECT_EQ(sum.tallies()[0].accepted, 3);
  EXPECT_EQ(sum.tallies()[1].proposed, 12);
  EXPECT_EQ(sum.tallies()[1].accepted, 5);

  std::string why;
  for (MutationTally bad : {MutationTally{"lens", 3, 4}, MutationTally{"lens", -1, 0},
                            MutationTally{"", 1, 1}, MutationTally{std::string(40, 'x'), 1, 1}}) {
    ChainFlush c = makeFlush(0, 1, 1.0f);
    c.tallies = {bad};
    EXPECT_EQ(sum.add(c, &why), FlushOutcome::kBadValues) << bad.name;
    EXPECT_NE(why.find("tally"), std::string::npos) << why;
  }
  ChainFlush many = makeFlush(0, 1, 1.0f);
  for (size_t i = 0; i <= kMaxTallyKinds; ++i)
    many.tallies.push_back({"kind" + std::to_string(i), 1, 1});
  EXPECT_EQ(sum.add(many, &why), FlushOutcome::kBadValues);
  EXPECT_EQ(sum.workDone(), 200);
  EXPECT_EQ(sum.tallies()[1].proposed, 12);
}

TEST(SplatAggregator, CountsRejectedSplatsByCause) {
  SplatAggregator sum(2, 2, 2);
  ChainFlush a = makeFlush(0, 0, 1.0f);
  a.rejected.nan = 2;
  a.rejected.negative = 1;
  ChainFlush b = makeFlush(1, 0, 1.0f);
  b.rejected.infinite = 5;
  EXPECT_EQ(sum.add(a), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(a), FlushOutcome::kDuplicate);  // counted once
  EXPECT_EQ(sum.add(b), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.rejected().nan, 2);
  EXPECT_EQ(sum.rejected().infinite, 5);
  EXPECT_EQ(sum.rejected().negative, 1);
  EXPECT_EQ(sum.rejected().total(), 8);
}

// Where invalid splats are made they are told apart: NaN first, then infinity, then a negative
// channel; valid values pass.
TEST(InvalidSplats, ClassifiesByCause) {
  InvalidSplats c;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_TRUE(c.check(Spectrum(1, 0, 2)));
  EXPECT_FALSE(c.check(Spectrum(nan, inf, -1)));
  EXPECT_FALSE(c.check(Spectrum(1, inf, -1)));
  EXPECT_FALSE(c.check(Spectrum(0, -1e-9f, 1)));
  EXPECT_FALSE(c.check(Spectrum(-inf, 0, 0)));
  EXPECT_EQ(c.nan, 1);
  EXPECT_EQ(c.infinite, 2);
  EXPECT_EQ(c.negative, 1);
}

TEST(SplatAggregator, SumsInDoublePrecision) {
  // 2^24 + 1 is not a float: a float accumulator would lose every one of the small additions.
  SplatAggregator sum(1, 1, 2);
  EXPECT_EQ(sum.add(makeFlush(0, 0, 16777216.0f, 1, 1)), FlushOutcome::kAccepted);
  for (uint32_t i = 0; i < 1000; ++i) {
    ASSERT_EQ(sum.add(makeFlush(1, i, 1.0f, 1, 1)), FlushOutcome::kAccepted);
  }
  EXPECT_EQ(sum.sums()[0], 16777216.0 + 1000.0);
}

// The image is the sum of every accepted flush in double; with two or more error groups each
// group's film is its own flushes' sum in float (the batch-means estimate's input), and with one
// group there is no second film.
TEST(SplatAggregator, KeepsEachGroupsFilmBesideTheImage) {
  SplatAggregator sum(1, 1, std::vector<uint32_t>{0, 1, 1});
  EXPECT_EQ(sum.groups(), 2u);
  EXPECT_EQ(sum.add(makeFlush(0, 0, 3.0f, 1, 1)), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(makeFlush(1, 0, 5.0f, 1, 1)), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.add(makeFlush(2, 0, 0.25f, 1, 1)), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.sums(), std::vector<double>(3, 8.25));
  EXPECT_EQ(sum.groupSums(0), std::vector<float>(3, 3.0f));
  EXPECT_EQ(sum.groupSums(1), std::vector<float>(3, 5.25f));
  EXPECT_EQ(sum.groupWork(0), 100);
  EXPECT_EQ(sum.groupWork(1), 200);
  const SplatAggregator restored(1, 1, {0, 1, 1}, sum.snapshot());
  EXPECT_EQ(restored.sums(), sum.sums());
  EXPECT_EQ(restored.groupSums(1), sum.groupSums(1));

  SplatAggregator one(1, 1, 2);
  EXPECT_EQ(one.groups(), 1u);
  EXPECT_THROW(one.groupSums(0), std::out_of_range);
  EXPECT_TRUE(one.snapshot().groupSums.empty());
  // An ended job keeps its counts alone (SplatAggregator::snapshot(false)), and comes back with
  // no film of any size, whatever its groups.
  const SplatAggregator ended(0, 0, {0, 1, 1}, sum.snapshot(false));
  EXPECT_EQ(ended.groups(), 2u);
  EXPECT_EQ(ended.workDone(), 300);
  EXPECT_EQ(ended.groupWork(1), 200);
  EXPECT_TRUE(ended.sums().empty());
  EXPECT_TRUE(ended.groupSums(1).empty());
  // A snapshot whose group films do not match the job's groups is refused, not half-restored.
  SplatAggregator::Snapshot wrong = sum.snapshot();
  wrong.groupSums.pop_back();
  EXPECT_THROW(SplatAggregator(1, 1, {0, 1, 1}, wrong), std::invalid_argument);
}

// An allocation pilot's samples (PilotSamples) join the sums before any flush: the image's film
// is the pilot's plus the flushes', the pilot's group g joins group g mod groups, the work
// counts both and priorWork the pilot's, and a snapshot keeps the split. Once, before any flush.
TEST(SplatAggregator, APriorJoinsTheSumsOnceBeforeAnyFlush) {
  PilotSamples prior;
  prior.groupWork = {10, 20, 30, 40};
  prior.work = 100;
  for (int g = 0; g < 4; ++g) prior.groupSums.push_back(std::vector<float>(3, 1.0f + g));
  prior.sums = std::vector<double>(3, 1.0 + 2.0 + 3.0 + 4.0);
  SplatAggregator sum(1, 1, std::vector<uint32_t>{0, 1});
  sum.addPrior(prior);
  EXPECT_EQ(sum.workDone(), 100);
  EXPECT_EQ(sum.priorWork(), 100);
  EXPECT_EQ(sum.acceptedFlushes(), 0u);
  EXPECT_EQ(sum.groupWork(0), 10 + 30);
  EXPECT_EQ(sum.groupWork(1), 20 + 40);
  EXPECT_EQ(sum.groupSums(0), std::vector<float>(3, 1.0f + 3.0f));
  EXPECT_EQ(sum.groupSums(1), std::vector<float>(3, 2.0f + 4.0f));
  EXPECT_THROW(sum.addPrior(prior), std::logic_error) << "twice";
  EXPECT_EQ(sum.add(makeFlush(1, 0, 0.5f, 1, 1)), FlushOutcome::kAccepted);
  EXPECT_EQ(sum.sums(), std::vector<double>(3, 10.5));
  EXPECT_EQ(sum.groupSums(1), std::vector<float>(3, 6.5f));
  EXPECT_EQ(sum.workDone(), 200);
  EXPECT_EQ(sum.groupWork(1), 160);
  EXPECT_EQ(sum.priorWork(), 100) << "the chains' work is not the prior's";

  // A restart reads the split back with the films (a checkpoint holds both or neither).
  const SplatAggregator restored(1, 1, {0, 1}, sum.snapshot());
  EXPECT_EQ(restored.priorWork(), 100);
  EXPECT_EQ(restored.workDone(), 200);
  EXPECT_EQ(restored.sums(), sum.sums());
  SplatAggregator::Snapshot inconsistent = sum.snapshot();
  inconsistent.priorWork = 201;
  EXPECT_THROW(SplatAggregator(1, 1, {0, 1}, inconsistent), std::invalid_argument);

  // After a flush it would count a second time in a restored job: refused.
  SplatAggregator late(1, 1, std::vector<uint32_t>{0, 1});
  EXPECT_EQ(late.add(makeFlush(0, 0, 1.0f, 1, 1)), FlushOutcome::kAccepted);
  EXPECT_THROW(late.addPrior(prior), std::logic_error);
  // One group: the pilot's groups all join the image's film, which is that group's.
  SplatAggregator one(1, 1, 2);
  one.addPrior(prior);
  EXPECT_EQ(one.groupWork(0), 100);
  EXPECT_EQ(one.sums(), std::vector<double>(3, 10.0));
  // Counts that do not add up, or a film of another size, change nothing.
  for (int broken = 0; broken < 3; ++broken) {
    PilotSamples bad = prior;
    if (broken == 0) bad.work = 99;
    if (broken == 1) bad.sums.pop_back();
    if (broken == 2) bad.groupSums[3].push_back(0);
    SplatAggregator fresh(1, 1, std::vector<uint32_t>{0, 1});
    EXPECT_THROW(fresh.addPrior(bad), std::invalid_argument) << broken;
    EXPECT_EQ(fresh.workDone(), 0) << broken;
    EXPECT_EQ(fresh.sums(), std::vector<double>(3, 0.0)) << broken;
  }
}

}  // namespace
}  // namespace farm
