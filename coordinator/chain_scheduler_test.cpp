#include "coordinator/chain_scheduler.h"

#include <gtest/gtest.h>

namespace farm {
namespace {

using std::chrono::seconds;

std::vector<ChainSpec> plan(int n) {
  std::vector<ChainSpec> chains(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    chains[size_t(i)].jobId = "job";
    chains[size_t(i)].chainIndex = uint32_t(i);
    chains[size_t(i)].budget = 1000;
    chains[size_t(i)].flushInterval = 100;
  }
  return chains;
}

TEST(ChainScheduler, LeasesEachChainToOneWorkerAtATime) {
  ChainScheduler scheduler(plan(3), seconds(10));
  const auto t0 = SteadyClock::time_point{} + seconds(1000);
  auto a = scheduler.lease("a", 2, t0);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].spec.chainIndex, 0u);
  EXPECT_EQ(a[1].spec.chainIndex, 1u);
  auto b = scheduler.lease("b", 5, t0);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].spec.chainIndex, 2u);
  EXPECT_TRUE(scheduler.lease("c", 5, t0).empty());
  EXPECT_EQ(scheduler.leasedCount(), 3u);
  EXPECT_TRUE(scheduler.holds("a", 0, a[0].epoch));
  EXPECT_FALSE(scheduler.holds("b", 0, a[0].epoch));
}

TEST(ChainScheduler, ExpiredLeaseResumesAtTheLastAcceptedFlush) {
  ChainScheduler scheduler(plan(1), seconds(10));
  const auto t0 = SteadyClock::time_point{} + seconds(1000);
  auto first = scheduler.lease("a", 1, t0);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_TRUE(first[0].spec.resumeState.empty());
  EXPECT_EQ(first[0].spec.resumeFlushIndex, 0u);

  // Two flushes arrive, then the worker goes silent.
  scheduler.recordFlush(0, 0, 100, "state-after-100", false, "a", first[0].epoch, t0 + seconds(5));
  scheduler.recordFlush(0, 1, 100, "state-after-200", false, "a", first[0].epoch, t0 + seconds(9));
  // The flush at t0+9 s renewed the lease to t0+19 s.
  EXPECT_EQ(scheduler.expireLeases(t0 + seconds(18)), 0);
  EXPECT_EQ(scheduler.expireLeases(t0 + seconds(19)), 1);
  EXPECT_EQ(scheduler.waitingCount(), 1u);

  auto second = scheduler.lease("b", 1, t0 + seconds(20));
  ASSERT_EQ(second.size(), 1u);
  EXPECT_EQ(second[0].spec.chainIndex, 0u);
  EXPECT_EQ(second[0].spec.resumeState, "state-after-200");
  EXPECT_EQ(second[0].spec.resumeMutations, 200);
  EXPECT_EQ(second[0].spec.resumeFlushIndex, 2u);
  EXPECT_GT(second[0].epoch, first[0].epoch);
  // The old holder lost the lease; renewals tell it so.
  EXPECT_FALSE(scheduler.renew("a", 0, first[0].epoch, t0 + seconds(21)));
  EXPECT_TRUE(scheduler.renew("b", 0, second[0].epoch, t0 + seconds(21)));

  scheduler.recordFlush(0, 2, 800, "done", true, "b", second[0].epoch, t0 + seconds(22));
  EXPECT_TRUE(scheduler.allFinished());
  EXPECT_EQ(scheduler.chainMutations(0), 1000);
}

TEST(ChainScheduler, RenewalKeepsALeaseAlive) {
  ChainScheduler scheduler(plan(1), seconds(10));
  const auto t0 = SteadyClock::time_point{} + seconds(1000);
  auto lease = scheduler.lease("a", 1, t0);
  ASSERT_TRUE(scheduler.renew("a", 0, lease[0].epoch, t0 + seconds(8)));
  EXPECT_EQ(scheduler.expireLeases(t0 + seconds(15)), 0);
  EXPECT_EQ(scheduler.expireLeases(t0 + seconds(18)), 1);
}

TEST(ChainScheduler, StopEndsWaitingChainsAndExpiredLeases) {
  ChainScheduler scheduler(plan(3), seconds(10));
  const auto t0 = SteadyClock::time_point{} + seconds(1000);
  auto lease = scheduler.lease("a", 1, t0);
  scheduler.stop();
  EXPECT_TRUE(scheduler.lease("b", 3, t0).empty());
  EXPECT_EQ(scheduler.finishedCount(), 2u);
  EXPECT_FALSE(scheduler.allFinished());
  scheduler.expireLeases(t0 + seconds(11));
  EXPECT_TRUE(scheduler.allFinished());
}

TEST(ChainScheduler, YieldedChainsTakeTurnsLeastWorkFirst) {
  // Time-limited jobs have more chains than threads: a chain that yields goes back in the queue
  // and the chain with the least work done is leased next, resuming where it stopped.
  std::vector<ChainSpec> chains = plan(3);
  for (ChainSpec& c : chains) c.budget = -1;
  ChainScheduler scheduler(chains, seconds(10));
  const auto t0 = SteadyClock::time_point{} + seconds(1000);
  auto a = scheduler.lease("a", 1, t0);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].spec.chainIndex, 0u);
  scheduler.recordFlush(0, 0, 100, "chain0-after-100", false, "a", a[0].epoch, t0);
  scheduler.yieldChain(0);
  EXPECT_FALSE(scheduler.holds("a", 0, a[0].epoch));
  EXPECT_EQ(scheduler.waitingCount(), 3u);
  auto next = scheduler.lease("a", 1, t0);
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].spec.chainIndex, 1u);  // chain 0 has done more
  scheduler.recordFlush(1, 0, 100, "chain1-after-100", false, "a", next[0].epoch, t0);
  scheduler.yieldChain(1);
  next = scheduler.lease("a", 1, t0);
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].spec.chainIndex, 2u);
  scheduler.recordFlush(2, 0, 100, "chain2-after-100", false, "a", next[0].epoch, t0);
  scheduler.yieldChain(2);
  next = scheduler.lease("a", 1, t0);
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].spec.chainIndex, 0u);
  EXPECT_EQ(next[0].spec.resumeState, "chain0-after-100");
  EXPECT_EQ(next[0].spec.resumeMutations, 100);
  EXPECT_EQ(next[0].spec.resumeFlushIndex, 1u);
}

TEST(ChainScheduler, AWorkerGetsWholeGroupsAndTheLeastServedGroupFirst) {
  // Eight chains in four error groups of two (as planned: contiguous).
  std::vector<ChainSpec> chains = plan(8);
  for (ChainSpec& c : chains) c.errorGroup = c.chainIndex / 2;
  auto groupsOf = [](const std::vector<ChainLease>& leases) {
    std::vector<uint32_t> g;
    for (const ChainLease& l : leases) g.push_back(l.spec.errorGroup);
    return g;
  };
  const auto t0 = SteadyClock::time_point{} + seconds(1000);
  {
    // A worker of few threads, one chain at a time: every group has a chain running before
    // any group has two, so that every group has work to show early.
    ChainScheduler scheduler(chains, seconds(10));
    std::vector<uint32_t> order;
    for (int i = 0; i < 4; ++i) {
      auto one = scheduler.lease("a", 1, t0);
      ASSERT_EQ(one.size(), 1u);
      order.push_back(one[0].spec.errorGroup);
    }
    EXPECT_EQ(order, (std::vector<uint32_t>{0, 1, 2, 3}));
    // A chain of group 1 ends: group 1 is now the least served.
    scheduler.finishChain(2);
    auto next = scheduler.lease("a", 1, t0);
    ASSERT_EQ(next.size(), 1u);
    EXPECT_EQ(next[0].spec.errorGroup, 1u);
  }
  {
    // Workers that take a group or more at once get whole groups: their chains batch.
    ChainScheduler scheduler(chains, seconds(10));
    EXPECT_EQ(groupsOf(scheduler.lease("a", 2, t0)), (std::vector<uint32_t>{0, 0}));
    EXPECT_EQ(groupsOf(scheduler.lease("b", 4, t0)), (std::vector<uint32_t>{1, 1, 2, 2}));
    EXPECT_EQ(groupsOf(scheduler.lease("c", 4, t0)), (std::vector<uint32_t>{3, 3}));
  }
}

}  // namespace
}  // namespace farm
