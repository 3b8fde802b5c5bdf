// --log-format json: every line farm-coordinator and farm-worker write to stderr is one JSON
// object with time, level, program and message, also when a message carries a quote (a scene
// named we"ird scene.xml) - what a log collector needs.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/test_support.h"

namespace farm::testing {
namespace {

using std::chrono::seconds;

// Each line of `path` parsed; fails the test on a line that is not a JSON object.
std::vector<nlohmann::json> jsonLines(const std::string& path) {
  std::vector<nlohmann::json> out;
  std::istringstream in(readFile(path));
  std::string line;
  while (std::getline(in, line)) {
    nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    EXPECT_FALSE(j.is_discarded()) << path << ": not JSON: " << line;
    if (j.is_discarded()) continue;
    for (const char* key : {"time", "level", "program", "message"}) {
      EXPECT_TRUE(j.contains(key)) << path << ": no " << key << " in " << line;
    }
    out.push_back(j);
  }
  return out;
}

TEST(StructuredLog, JsonLinesStayValidWithQuotesInAMessage) {
  ScratchDir scratch("json-log");
  const std::string folder = scratch / "scene";
  std::filesystem::create_directories(folder);
  const std::string scene = folder + "/we\"ird scene.xml";
  std::filesystem::copy_file(std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml", scene);
  CoordinatorProcess coordinator(scratch.path(), 5, 0, "coordinator", {"--log-format", "json"});
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();
  ChildProcess worker({FARM_WORKER_BIN, "--coordinator", coordinator.address(), "--threads", "1",
                       "--cache", scratch / "cache", "--log-format", "json"},
                      scratch / "worker.out", scratch / "worker.err");
  CommandResult submitted =
      runCommand({FARM_CLI_BIN, "submit", "--coordinator", coordinator.address(), scene,
                  "--algorithm", "pt", "--width", "16", "--height", "16", "--spp", "4"},
                 seconds(60), scratch.path());
  ASSERT_EQ(submitted.exitCode, 0) << submitted.err;
  CommandResult fetched =
      runCommand({FARM_CLI_BIN, "fetch", "--coordinator", coordinator.address(),
                  lastLine(submitted.out), "-o", scratch / "out.exr", "--timeout", "60"},
                 seconds(90), scratch.path());
  ASSERT_EQ(fetched.exitCode, 0) << fetched.err;
  EXPECT_EQ(worker.stop(seconds(20)), 0);
  EXPECT_EQ(coordinator.process().stop(), 0);

  const std::vector<nlohmann::json> coordinatorLines = jsonLines(scratch / "coordinator.err");
  const std::vector<nlohmann::json> workerLines = jsonLines(scratch / "worker.err");
  ASSERT_GE(coordinatorLines.size(), 3u);
  ASSERT_GE(workerLines.size(), 2u);
  bool named = false;
  for (const nlohmann::json& j : coordinatorLines) {
    EXPECT_EQ(j["program"], "farm-coordinator");
    named |= j["message"].get<std::string>().find("we\"ird scene.xml") != std::string::npos;
  }
  EXPECT_TRUE(named) << "no message names the scene, its quote intact";
  for (const nlohmann::json& j : workerLines) EXPECT_EQ(j["program"], "farm-worker");
  EXPECT_EQ(coordinatorLines.back()["message"], "SIGTERM, shutting down");
}

}  // namespace
}  // namespace farm::testing
