#pragma once
// What the tests that drive a Coordinator in process share (coordinator/*_test.cpp,
// worker/flush_batch_test.cpp): a worker that takes every algorithm, and a job submitted and
// waited for until its chains can be leased.
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>

#include "coordinator/coordinator.h"

namespace farm {

// Registers a worker of `threads` threads that takes every algorithm; its id.
inline std::string registerTestWorker(Coordinator& coordinator, int threads) {
  WorkerInfo info;
  info.threads = threads;
  for (Algorithm a : allAlgorithms()) info.capabilities.insert(a);
  std::string id;
  EXPECT_TRUE(coordinator.registerWorker(info, &id).isOk());
  return id;
}

// Submits `spec` and waits (a minute at most) until the job renders, that is until its chains
// can be leased; a job that ends before that fails the test. The job's id.
inline std::string submitAndWaitForRendering(Coordinator& coordinator, JobSpec spec) {
  std::string id;
  const Status s = coordinator.submit(std::move(spec), &id);
  EXPECT_TRUE(s.isOk()) << s.message();
  for (int i = 0; i < 1200; ++i) {
    JobProgress p;
    coordinator.progress(id, 0, &p);
    if (p.phase == JobPhase::kRendering) return id;
    EXPECT_FALSE(isTerminal(p.phase)) << p.error;
    if (isTerminal(p.phase)) return id;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ADD_FAILURE() << "the job did not start rendering";
  return id;
}

}  // namespace farm
