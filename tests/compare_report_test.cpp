// `farm compare` and `farm report` as a user runs them: real processes (the farm command, and a
// coordinator with a worker for the remote forms), real renders, and the report directory's
// files: each algorithm's CSV and image, a chart with one curve per algorithm (matplotlib's SVG,
// each curve's group named), summary.json and the page that shows them.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/test_support.h"

namespace farm::testing {
namespace {

using std::chrono::seconds;
namespace fs = std::filesystem;

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// The report directory holds one entry per algorithm, a chart of as many curves, and a page
// that shows them.
void expectReport(const std::string& dir, const std::vector<std::string>& algorithms) {
  for (const std::string& a : algorithms) {
    const std::string csv = readFile(dir + "/" + a + "/error_vs_time.csv");
    EXPECT_EQ(csv.rfind("elapsed_seconds,samples,rmse,relmse,estimated_relmse\n", 0), 0u) << a;
    EXPECT_GE(count(csv, "\n"), 2u) << a << ": no error sample";
    EXPECT_TRUE(fs::is_regular_file(dir + "/" + a + "/image.exr")) << a;
    EXPECT_TRUE(fs::is_regular_file(dir + "/" + a + "/image.png")) << a;
    EXPECT_TRUE(fs::is_regular_file(dir + "/" + a + "/report.json")) << a;
  }
  ASSERT_TRUE(fs::is_regular_file(dir + "/error_vs_time.png"));
  const std::string svg = readFile(dir + "/error_vs_time.svg");
  EXPECT_EQ(count(svg, "id=\"curve-"), algorithms.size()) << "one curve per algorithm";
  for (const std::string& a : algorithms)
    EXPECT_NE(svg.find("id=\"curve-" + a + "\""), std::string::npos) << a;
  const std::string html = readFile(dir + "/index.html");
  EXPECT_NE(html.find("error_vs_time.svg"), std::string::npos);
  for (const std::string& a : algorithms)
    EXPECT_NE(html.find(a + "/image.png"), std::string::npos) << a;
  const nlohmann::json summary = nlohmann::json::parse(readFile(dir + "/summary.json"));
  ASSERT_EQ(summary.size(), algorithms.size());
  for (size_t i = 0; i < algorithms.size(); ++i) {
    EXPECT_EQ(summary[i]["name"], algorithms[i]);
    EXPECT_EQ(summary[i]["phase"], "done");
    EXPECT_TRUE(summary[i]["estimated_relmse"].is_number()) << algorithms[i];
  }
}

TEST(FarmCompare, RendersEachAlgorithmAndWritesTheReport) {
  ScratchDir scratch("compare");
  const std::string dir = scratch / "report";
  CommandResult r =
      runCommand({FARM_CLI_BIN, "compare", kScene, "--algorithms", "pt,bdpt,pssmlt,auto", "--pilot",
                  "--combine-large-steps", "--width", "48", "--height", "48", "--spp", "8", "--mpp",
                  "8", "--threads", "2", "--report", dir},
                 seconds(180), scratch.path());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err.find("no chart"), std::string::npos) << r.err;
  expectReport(dir, {"pt", "bdpt", "pssmlt", "auto"});
  // Each job's plan is on the page, auto's with its pilot (--pilot is auto's alone).
  const std::string html = readFile(dir + "/index.html");
  EXPECT_EQ(count(html, "<h3>"), 4u);  // the Cornell box: pt, bdpt and pssmlt, a second each
  EXPECT_NE(html.find("left out: lens sampling"), std::string::npos);
  EXPECT_NE(html.find("(auto)"), std::string::npos);
  EXPECT_NE(html.find("pilot pt: "), std::string::npos);
  const nlohmann::json report = nlohmann::json::parse(readFile(dir + "/auto/report.json"));
  EXPECT_FALSE(report["render_plan"].empty());
  // --combine-large-steps goes to the chains with large steps (and auto) alone.
  for (const char* a : {"pt", "bdpt", "pssmlt"}) {
    const nlohmann::json j =
        nlohmann::json::parse(readFile(dir + "/" + std::string(a) + "/report.json"));
    EXPECT_EQ(j["settings"]["combine_large_steps"], std::string(a) == "pssmlt") << a;
  }

  // What it refuses, before rendering anything.
  CommandResult bad = runCommand(
      {FARM_CLI_BIN, "compare", kScene, "--algorithms", "pt,photon", "--report", scratch / "bad"},
      seconds(30), scratch.path());
  EXPECT_NE(bad.exitCode, 0);
  EXPECT_NE(bad.err.find("'photon' is not one of"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(scratch / "bad"));
}

// `farm plan` on each shared scene: what it has, the algorithm, and each part left out with
// its reason.
TEST(FarmPlan, EachSharedSceneNamesWhatItLeavesOut) {
  ScratchDir scratch("plan");
  const std::string scenes = std::string(FARM_SHARED_DIR) + "/scenes/";
  for (const std::string scene :
       {"cornell-box/scene.xml", "veach-bidir/scene.xml", "veach-mis/scene.xml",
        "veach-ajar/scene.pbrt", "water-caustic/scene.xml"}) {
    CommandResult r = runCommand({FARM_CLI_BIN, "plan", scenes + scene, "--algorithm", "mlt"},
                                 seconds(60), scratch.path());
    ASSERT_EQ(r.exitCode, 0) << scene << ": " << r.err;
    for (const char* what :
         {"surfaces: ", "lights: ", "camera: pinhole", "textures: ", "shading normals: strict, ",
          "environment: none", "media: 0 homogeneous, 0 grid", "algorithm: mlt (requested)",
          "mutations: bidir=", "left out: lens sampling (pinhole camera",
          "left out: escaped-path handling (no environment", "left out: medium tracking (no media"})
      EXPECT_NE(r.out.find(what), std::string::npos) << scene << " lacks '" << what << "':\n"
                                                     << r.out;
  }
  CommandResult cornell =
      runCommand({FARM_CLI_BIN, "plan", scenes + "cornell-box/scene.xml", "--algorithm", "mlt"},
                 seconds(60), scratch.path());
  EXPECT_NE(cornell.out.find("left out: manifold perturbation (no specular surfaces"),
            std::string::npos)
      << cornell.out;
  EXPECT_NE(cornell.out.find("multichain=0,manifold=0"), std::string::npos) << cornell.out;
  CommandResult water =
      runCommand({FARM_CLI_BIN, "plan", scenes + "water-caustic/scene.xml", "--json"}, seconds(60),
                 scratch.path());
  ASSERT_EQ(water.exitCode, 0) << water.err;
  const nlohmann::json j = nlohmann::json::parse(water.out);
  EXPECT_EQ(j["algorithm"], "mlt");
  EXPECT_EQ(j["candidates"], nlohmann::json::array({"mlt"}));
  EXPECT_TRUE(j["automatic"].get<bool>());

  CommandResult bad =
      runCommand({FARM_CLI_BIN, "plan", scenes + "cornell-box/scene.xml", "--algorithm", "photon"},
                 seconds(30), scratch.path());
  EXPECT_EQ(bad.exitCode, 2);
  EXPECT_NE(bad.err.find("or auto, not 'photon'"), std::string::npos) << bad.err;
  // A scene that erpt cannot render: an environment around a medium.
  const std::string foggySky = scratch / "foggy-sky.pbrt";
  std::ofstream(foggySky)
      << "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
         "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" "
         "[0.1 0.1 0.1] \"rgb sigma_s\" [0.1 0.1 0.1]\n"
         "LightSource \"infinite\"\nShape \"sphere\"\n";
  CommandResult refused = runCommand({FARM_CLI_BIN, "plan", foggySky, "--algorithm", "erpt"},
                                     seconds(30), scratch.path());
  EXPECT_EQ(refused.exitCode, 1);
  EXPECT_NE(refused.err.find("an environment light in a scene with media is not supported by erpt"),
            std::string::npos)
      << refused.err;
  // Through a density grid it plans.
  CommandResult grid =
      runCommand({FARM_CLI_BIN, "plan", std::string(FARM_TEST_DATA_DIR) + "/smoke-room/scene.xml",
                  "--algorithm", "erpt"},
                 seconds(30), scratch.path());
  EXPECT_EQ(grid.exitCode, 0) << grid.err;
}

TEST(FarmCompare, RendersOnACoordinatorAndReportsAJob) {
  ScratchDir scratch("compare-remote");
  CoordinatorProcess coordinator(scratch.path());
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();
  ChildProcess worker({FARM_WORKER_BIN, "--coordinator", coordinator.address(), "--threads", "2",
                       "--cache", scratch / "cache"},
                      scratch / "worker.log", scratch / "worker.log");
  const std::string dir = scratch / "report";
  CommandResult r = runCommand({FARM_CLI_BIN, "compare", kScene, "--algorithms", "bdpt,mlt",
                                "--coordinator", coordinator.address(), "--width", "48", "--height",
                                "48", "--spp", "4", "--mpp", "8", "--report", dir},
                               seconds(180), scratch.path());
  ASSERT_EQ(r.exitCode, 0) << r.err << "\n" << coordinator.log();
  expectReport(dir, {"bdpt", "mlt"});

  // farm report of a job submitted on its own: the same files for its one algorithm.
  CommandResult submitted =
      runCommand({FARM_CLI_BIN, "submit", "--coordinator", coordinator.address(), kScene,
                  "--algorithm", "pssmlt", "--width", "48", "--height", "48", "--mpp", "8"},
                 seconds(60), scratch.path());
  ASSERT_EQ(submitted.exitCode, 0) << submitted.err;
  const std::string job = lastLine(submitted.out);
  CommandResult fetched = runCommand({FARM_CLI_BIN, "fetch", "--coordinator", coordinator.address(),
                                      job, "-o", scratch / "job.exr"},
                                     seconds(120), scratch.path());
  ASSERT_EQ(fetched.exitCode, 0) << fetched.err;
  CommandResult reported = runCommand(
      {FARM_CLI_BIN, "report", "--coordinator", coordinator.address(), job, scratch / "job"},
      seconds(60), scratch.path());
  ASSERT_EQ(reported.exitCode, 0) << reported.err;
  expectReport(scratch / "job", {"pssmlt"});
  CommandResult unknown = runCommand(
      {FARM_CLI_BIN, "report", "--coordinator", coordinator.address(), "job-nope", scratch / "x"},
      seconds(60), scratch.path());
  EXPECT_NE(unknown.exitCode, 0);
  EXPECT_NE(unknown.err.find("job-nope"), std::string::npos) << unknown.err;
  EXPECT_EQ(worker.stop(seconds(20)), 0);
}

}  // namespace
}  // namespace farm::testing
