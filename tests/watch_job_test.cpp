// WatchJob against a real coordinator and worker: the stream follows a job to its end, phases
// and fractions only move forward, every error sample arrives exactly once, the workers running
// it are counted; `farm watch` shows it and exits 0; a watch open at shutdown does not hold the
// coordinator up.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "proto/farm.grpc.pb.h"
#include "tests/test_support.h"

namespace farm::testing {
namespace {

using std::chrono::seconds;

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

std::unique_ptr<v1::ClientApi::Stub> clientStub(const std::string& address) {
  return v1::ClientApi::NewStub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
}

std::string submit(const std::string& address, const std::string& scratch,
                   const std::vector<std::string>& settings) {
  std::vector<std::string> argv = {FARM_CLI_BIN, "submit", "--coordinator", address, kScene};
  argv.insert(argv.end(), settings.begin(), settings.end());
  CommandResult r = runCommand(argv, seconds(60), scratch);
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return lastLine(r.out);
}

TEST(WatchJob, FollowsAJobToItsEndWithEachErrorSampleOnce) {
  ScratchDir scratch("watch");
  CoordinatorProcess coordinator(scratch.path());
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();
  const std::string address = coordinator.address();
  ChildProcess worker(
      {FARM_WORKER_BIN, "--coordinator", address, "--threads", "2", "--cache", scratch / "cache"},
      scratch / "worker.log", scratch / "worker.log");
  const std::string job = submit(address, scratch.path(),
                                 {"--algorithm", "pssmlt", "--width", "64", "--height", "48",
                                  "--mpp", "256", "--seed", "2", "--flush-every", "20000"});
  ASSERT_EQ(job.rfind("job-", 0), 0u) << job;

  auto stub = clientStub(address);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + seconds(120));
  v1::WatchJobRequest request;
  request.set_job_id(job);
  request.set_interval_ms(150);
  auto reader = stub->WatchJob(&context, request);
  std::vector<v1::JobProgress> messages;
  v1::JobProgress m;
  while (reader->Read(&m)) messages.push_back(m);
  grpc::Status status = reader->Finish();
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_GE(messages.size(), 3u);
  EXPECT_EQ(messages.back().phase(), v1::DONE);
  EXPECT_DOUBLE_EQ(messages.back().fraction(), 1.0);
  size_t samples = 0;
  bool sawWorker = false;
  for (size_t i = 0; i < messages.size(); ++i) {
    samples += size_t(messages[i].error_series_size());
    sawWorker |= messages[i].phase() == v1::RENDERING && messages[i].active_workers() == 1;
    if (i == 0) continue;
    EXPECT_GE(messages[i].phase(), messages[i - 1].phase()) << "message " << i;
    EXPECT_GE(messages[i].fraction(), messages[i - 1].fraction()) << "message " << i;
    EXPECT_GE(messages[i].work_done(), messages[i - 1].work_done()) << "message " << i;
  }
  EXPECT_EQ(samples, size_t(messages.back().error_series_total()))
      << "each error sample is sent once, and all are sent";
  EXPECT_GT(samples, 1u);
  EXPECT_TRUE(sawWorker) << "a rendering message counts the one worker";

  // The same through the CLI, on the finished job; and status says each tally once.
  CommandResult watched =
      runCommand({FARM_CLI_BIN, "watch", "--coordinator", address, job, "--interval", "0.2"},
                 seconds(30), scratch.path());
  EXPECT_EQ(watched.exitCode, 0) << watched.err;
  EXPECT_NE(watched.out.find("done"), std::string::npos) << watched.out;
  EXPECT_NE(watched.err.find("100.0%"), std::string::npos) << watched.err;
  CommandResult status2 = runCommand({FARM_CLI_BIN, "status", "--coordinator", address, job},
                                     seconds(30), scratch.path());
  ASSERT_EQ(status2.exitCode, 0) << status2.err;
  const size_t first = status2.out.find("small step");
  ASSERT_NE(first, std::string::npos) << status2.out;
  EXPECT_EQ(status2.out.find("small step", first + 1), std::string::npos) << status2.out;

  // Unknown and malformed ids.
  for (const auto& [id, code] : std::vector<std::pair<std::string, grpc::StatusCode>>{
           {"job-000000000000", grpc::StatusCode::NOT_FOUND},
           {"", grpc::StatusCode::INVALID_ARGUMENT},
           {std::string(300, 'j'), grpc::StatusCode::INVALID_ARGUMENT}}) {
    grpc::ClientContext c;
    c.set_deadline(std::chrono::system_clock::now() + seconds(10));
    v1::WatchJobRequest r;
    r.set_job_id(id);
    auto rd = stub->WatchJob(&c, r);
    while (rd->Read(&m)) {
    }
    EXPECT_EQ(rd->Finish().error_code(), code) << id;
  }
  EXPECT_EQ(worker.stop(seconds(20)), 0);
}

TEST(WatchJob, AWatchOpenAtShutdownEndsWithTheCoordinator) {
  ScratchDir scratch("watch-shutdown");
  CoordinatorProcess coordinator(scratch.path());
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();
  // No worker: the job waits in rendering for ever.
  const std::string job = submit(coordinator.address(), scratch.path(),
                                 {"--algorithm", "pt", "--width", "16", "--height", "16"});
  ChildProcess watcher(
      {FARM_CLI_BIN, "watch", "--coordinator", coordinator.address(), job, "--interval", "10"},
      scratch / "watch.out", scratch / "watch.err");
  std::this_thread::sleep_for(seconds(1));
  const auto before = std::chrono::steady_clock::now();
  EXPECT_EQ(coordinator.process().stop(seconds(10)), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - before, seconds(2))
      << "the open watch held the shutdown up";
  EXPECT_NE(watcher.wait(std::chrono::milliseconds(10000)), 0)
      << "the watcher must fail when the coordinator goes away";
  EXPECT_NE(readFile(scratch / "watch.err").find("shutting down"), std::string::npos)
      << readFile(scratch / "watch.err");
}

}  // namespace
}  // namespace farm::testing
