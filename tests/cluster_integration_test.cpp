// A real farm-coordinator and two real farm-worker processes on loopback render the Cornell
// box; the EXR fetched from the coordinator must agree with `farm render` of the same job and
// seed, up to float summation order (docs/design.md: the image depends on scene, settings, seed and
// chain budgets only, not on the number of workers).
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <utility>

#include "common/film/image.h"
#include "common/film/pixel_allocation.h"
#include "tests/test_support.h"

namespace farm::testing {
namespace {

using std::chrono::seconds;

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

struct ClusterCase {
  ClusterCase(std::string a, std::vector<std::string> b, std::string s = kScene, std::string n = "")
      : algorithm(std::move(a)), budget(std::move(b)), scene(std::move(s)), name(std::move(n)) {}
  std::string algorithm;
  std::vector<std::string> budget;  // --spp N or --mpp N
  std::string scene;
  std::string name;  // the test's name when not the algorithm's
  // Render with a pixel allocation (a checkerboard of pt and bdpt cells at several densities):
  // each worker must receive it once and draw every chain's film points from it.
  bool pixelAllocation = false;
};

ClusterCase withPixelAllocation(ClusterCase c) {
  c.pixelAllocation = true;
  return c;
}

// Writes the allocation of a ClusterCase (a 64x48 film in 8x8 cells) to `path`.
void writeCheckerboardAllocation(const std::string& path) {
  const int cells = 8 * 6;
  std::vector<float> density(cells);
  std::vector<uint8_t> bidirectional(cells);
  for (int i = 0; i < cells; ++i) {
    density[size_t(i)] = 0.25f + float(i % 5);
    bidirectional[size_t(i)] = uint8_t((i + i / 8) % 2);
  }
  std::ofstream(path, std::ios::binary)
      << PixelAllocation(64, 48, 8, density, bidirectional).encode();
}

void PrintTo(const ClusterCase& c, std::ostream* os) {
  *os << c.algorithm << " " << c.scene;
}

class ClusterTest : public ::testing::TestWithParam<ClusterCase> {};

// `farm submit` of the Cornell box with `settings`; the job id (the last line of stdout), or
// the command's error output when it failed.
std::string submitJob(const std::string& address, const std::vector<std::string>& settings,
                      const std::string& scratch, const std::string& scene = kScene) {
  std::vector<std::string> submit = {FARM_CLI_BIN, "submit", "--coordinator", address, scene};
  submit.insert(submit.end(), settings.begin(), settings.end());
  CommandResult submitted = runCommand(submit, std::chrono::seconds(60), scratch);
  if (submitted.exitCode != 0) return "farm submit failed: " + submitted.err;
  return lastLine(submitted.out);
}

void expectImagesAgree(const Image& distributed, const Image& embedded) {
  ASSERT_EQ(distributed.width, embedded.width);
  ASSERT_EQ(distributed.height, embedded.height);
  double sumA = 0, sumB = 0, worst = 0;
  size_t compared = 0;
  for (size_t i = 0; i < embedded.rgb.size(); ++i) {
    const double a = distributed.rgb[i], b = embedded.rgb[i];
    ASSERT_TRUE(std::isfinite(a)) << "pixel value " << i;
    sumA += a;
    sumB += b;
    if (std::abs(b) > 1e-3) {
      worst = std::max(worst, std::abs(a - b) / std::abs(b));
      ++compared;
    }
  }
  EXPECT_GT(compared, embedded.rgb.size() / 4) << "the image is almost black";
  EXPECT_LT(worst, 1e-4) << "largest relative difference per pixel value";
  const double n = double(embedded.rgb.size());
  EXPECT_NEAR(sumA / n, sumB / n, 1e-5 * std::max(1.0, std::abs(sumB / n)));
}

TEST_P(ClusterTest, FetchedImageMatchesEmbeddedRender) {
  const ClusterCase& c = GetParam();
  ScratchDir scratch("cluster-" + c.algorithm);
  ASSERT_FALSE(scratch.path().empty());
  CoordinatorProcess coordinator(scratch.path());
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();

  std::vector<std::unique_ptr<ChildProcess>> workers;
  for (int i = 0; i < 2; ++i) {
    const std::string log = scratch / ("worker" + std::to_string(i) + ".log");
    workers.push_back(std::make_unique<ChildProcess>(
        std::vector<std::string>{FARM_WORKER_BIN, "--coordinator", coordinator.address(),
                                 "--threads", "2", "--cache",
                                 scratch / ("cache" + std::to_string(i))},
        log, log));
  }
  for (int i = 0; i < 2; ++i) {
    ASSERT_FALSE(
        waitForText(scratch / ("worker" + std::to_string(i) + ".log"), "registered", seconds(15))
            .empty())
        << "worker " << i << " did not register";
  }

  std::vector<std::string> settings = {"--algorithm", c.algorithm, "--width", "64",
                                       "--height",    "48",        "--seed",  "7"};
  settings.insert(settings.end(), c.budget.begin(), c.budget.end());
  if (c.pixelAllocation) {
    writeCheckerboardAllocation(scratch / "allocation.bin");
    settings.insert(settings.end(), {"--pixel-allocation", scratch / "allocation.bin"});
  }

  const std::string job = submitJob(coordinator.address(), settings, scratch.path(), c.scene);
  ASSERT_EQ(job.rfind("job-", 0), 0u) << "last line of stdout: " << job;

  CommandResult fetched = runCommand({FARM_CLI_BIN, "fetch", "--coordinator", coordinator.address(),
                                      job, "-o", scratch / "distributed.exr", "--timeout", "120"},
                                     seconds(130), scratch.path());
  ASSERT_EQ(fetched.exitCode, 0) << fetched.err << "\n" << coordinator.log();

  CommandResult status =
      runCommand({FARM_CLI_BIN, "status", "--coordinator", coordinator.address(), job, "--json"},
                 seconds(30), scratch.path());
  ASSERT_EQ(status.exitCode, 0) << status.err;
  EXPECT_NE(status.out.find("\"phase\": \"done\""), std::string::npos) << status.out;
  EXPECT_NE(status.out.find("\"fraction\": 1.0"), std::string::npos) << status.out;
  if (c.algorithm == "mlt") {  // the workers' acceptance tallies reach the job's status
    EXPECT_NE(status.out.find("\"bidir\""), std::string::npos) << status.out;
  }

  std::vector<std::string> render = {
      FARM_CLI_BIN, "render", c.scene, "-o", scratch / "embedded.exr", "--threads", "2"};
  render.insert(render.end(), settings.begin(), settings.end());
  CommandResult rendered = runCommand(render, seconds(120), scratch.path());
  ASSERT_EQ(rendered.exitCode, 0) << rendered.err;

  // Both workers did part of the job and leave cleanly on SIGTERM.
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(workers[size_t(i)]->stop(seconds(20)), 0) << "worker " << i;
    const std::string log = readFile(scratch / ("worker" + std::to_string(i) + ".log"));
    // The closing line must be there (a worker killed or hung writes none) and count chains.
    const size_t done = log.find("done: ");
    ASSERT_NE(done, std::string::npos) << "worker " << i << " never said it was done:\n" << log;
    EXPECT_GT(std::atoll(log.c_str() + done + 6), 0) << "worker " << i << " ran no chain:\n" << log;
  }

  Image distributed, embedded;
  std::string error;
  ImageMetadata metadata;
  ASSERT_TRUE(readExr(scratch / "distributed.exr", &distributed, &error, &metadata)) << error;
  ASSERT_TRUE(readExr(scratch / "embedded.exr", &embedded, &error)) << error;
  EXPECT_EQ(distributed.width, 64);
  EXPECT_EQ(distributed.height, 48);
  expectImagesAgree(distributed, embedded);
  if (c.pixelAllocation) {  // the image is the allocation's, not uniform sampling's
    EXPECT_NE(metadata.count("farm:pixelAllocation"), 0u);
    std::vector<std::string> uniform = {
        FARM_CLI_BIN, "render", c.scene, "-o", scratch / "uniform.exr", "--threads", "2"};
    uniform.insert(uniform.end(), settings.begin(), settings.end() - 2);
    ASSERT_EQ(runCommand(uniform, seconds(120), scratch.path()).exitCode, 0);
    Image other;
    ASSERT_TRUE(readExr(scratch / "uniform.exr", &other, &error)) << error;
    EXPECT_NE(other.rgb, distributed.rgb);
  }
  EXPECT_TRUE(std::filesystem::exists(scratch / "distributed.png"));
  EXPECT_TRUE(std::filesystem::exists(scratch / "embedded.png"));
  EXPECT_EQ(coordinator.process().stop(), 0);
}

// Work accepted so far, from `farm status --json`; -1 if it cannot be read.
int64_t workDone(const std::string& address, const std::string& job, const std::string& scratch) {
  CommandResult status = runCommand(
      {FARM_CLI_BIN, "status", "--coordinator", address, job, "--json"}, seconds(20), scratch);
  if (status.exitCode != 0) return -1;
  const std::string key = "\"work_done\": ";
  const size_t at = status.out.find(key);
  return at == std::string::npos ? -1 : std::atoll(status.out.c_str() + at + key.size());
}

// A worker killed in the middle of a job costs its leases' time and nothing else: its chains go
// to another worker, resume from their last accepted flush, and the image is the same.
class ClusterFailure : public ::testing::TestWithParam<ClusterCase> {};

TEST_P(ClusterFailure, KilledWorkerChangesNothingButTime) {
  const ClusterCase& c = GetParam();
  ScratchDir scratch("cluster-kill-" + c.algorithm);
  CoordinatorProcess coordinator(scratch.path(), /*leaseSeconds=*/1.5);
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();
  auto startWorker = [&](const std::string& name) {
    return std::make_unique<ChildProcess>(
        std::vector<std::string>{FARM_WORKER_BIN, "--coordinator", coordinator.address(),
                                 "--threads", "2", "--cache", scratch / ("cache-" + name)},
        scratch / (name + ".log"), scratch / (name + ".log"));
  };
  auto doomed = startWorker("doomed");
  ASSERT_FALSE(waitForText(scratch / "doomed.log", "registered", seconds(15)).empty());

  // 64x48: pt and mlt over 64 chains of 12288 samples or mutations each, flushed every 4096;
  // erpt over four tiles, flushed every 4096 seeds.
  std::vector<std::string> settings = {"--algorithm", c.algorithm, "--width", "64",
                                       "--height",    "48",        "--seed",  "3"};
  settings.insert(settings.end(), c.budget.begin(), c.budget.end());
  const std::string job = submitJob(coordinator.address(), settings, scratch.path(), c.scene);
  ASSERT_EQ(job.rfind("job-", 0), 0u) << "last line of stdout: " << job;

  const auto deadline = std::chrono::steady_clock::now() + seconds(60);
  while (workDone(coordinator.address(), job, scratch.path()) <= 0 &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  doomed->signal(SIGKILL);
  EXPECT_EQ(doomed->wait(seconds(10)), 128 + SIGKILL);
  const int64_t doneAtKill = workDone(coordinator.address(), job, scratch.path());
  EXPECT_GT(doneAtKill, 0);
  const int64_t total = int64_t(64) * 48 * std::stoll(c.budget.at(1));
  EXPECT_LT(doneAtKill, total) << "the worker finished before it could be killed";

  auto survivor = startWorker("survivor");
  CommandResult fetched = runCommand({FARM_CLI_BIN, "fetch", "--coordinator", coordinator.address(),
                                      job, "-o", scratch / "distributed.exr", "--timeout", "120"},
                                     seconds(130), scratch.path());
  ASSERT_EQ(fetched.exitCode, 0) << fetched.err << "\n" << coordinator.log();
  EXPECT_EQ(survivor->stop(seconds(20)), 0);

  std::vector<std::string> render = {
      FARM_CLI_BIN, "render", c.scene, "-o", scratch / "embedded.exr", "--threads", "2"};
  render.insert(render.end(), settings.begin(), settings.end());
  CommandResult rendered = runCommand(render, seconds(120), scratch.path());
  ASSERT_EQ(rendered.exitCode, 0) << rendered.err;

  Image distributed, embedded;
  std::string error;
  ASSERT_TRUE(readExr(scratch / "distributed.exr", &distributed, &error)) << error;
  ASSERT_TRUE(readExr(scratch / "embedded.exr", &embedded, &error)) << error;
  expectImagesAgree(distributed, embedded);
}

// A durable coordinator killed (SIGKILL) three times while it renders two jobs - once right
// after a submission, while that job bootstraps - and started again each time on its port and
// data directory: the workers reconnect on their own, no job's work done ever goes back, and
// both images are the ones `farm render` makes of the same jobs and seeds.
TEST(ClusterCoordinatorCrash, KilledCoordinatorResumesEveryJob) {
  ScratchDir scratch("coordinator-crash");
  auto coordinator = std::make_unique<CoordinatorProcess>(scratch.path(), /*leaseSeconds=*/2.0);
  ASSERT_TRUE(coordinator->ok()) << coordinator->log();
  const int port = std::stoi(coordinator->address().substr(coordinator->address().rfind(':') + 1));
  const std::string address = coordinator->address();
  std::vector<std::unique_ptr<ChildProcess>> workers;
  for (int i = 0; i < 2; ++i) {
    const std::string log = scratch / ("worker" + std::to_string(i) + ".log");
    workers.push_back(std::make_unique<ChildProcess>(
        std::vector<std::string>{FARM_WORKER_BIN, "--coordinator", address, "--threads", "1",
                                 "--cache", scratch / ("cache" + std::to_string(i))},
        log, log));
    ASSERT_FALSE(waitForText(log, "registered", seconds(15)).empty()) << "worker " << i;
  }

  const std::vector<std::vector<std::string>> jobSettings = {
      {"--algorithm", "mlt", "--width", "64", "--height", "48", "--seed", "5", "--mpp", "1024"},
      {"--algorithm", "pssmlt", "--width", "64", "--height", "48", "--seed", "6", "--mpp", "128"}};
  std::vector<std::string> jobs;
  jobs.push_back(submitJob(address, jobSettings[0], scratch.path()));
  ASSERT_EQ(jobs[0].rfind("job-", 0), 0u) << jobs[0];

  std::vector<int64_t> seen(2, 0);  // the most work done each job was seen with
  auto observe = [&](const std::string& when) {
    for (size_t j = 0; j < jobs.size(); ++j) {
      const int64_t done = workDone(address, jobs[j], scratch.path());
      EXPECT_GE(done, seen[j]) << "job " << j << "'s work done went back " << when;
      seen[j] = std::max(seen[j], done);
    }
  };
  for (int kill = 1; kill <= 3; ++kill) {
    SCOPED_TRACE("kill " + std::to_string(kill));
    if (kill == 2) {
      // Killed while the new job bootstraps: it is prepared again after the restart.
      jobs.push_back(submitJob(address, jobSettings[1], scratch.path()));
      ASSERT_EQ(jobs[1].rfind("job-", 0), 0u) << jobs[1];
    } else {
      // Killed once more flushes have come in (at whatever point the workers then are).
      const int64_t before = seen[0];
      const auto deadline = std::chrono::steady_clock::now() + seconds(60);
      while (std::chrono::steady_clock::now() < deadline) {
        observe("before kill " + std::to_string(kill));
        if (seen[0] > before) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
      ASSERT_GT(seen[0], before) << "no progress before kill " << kill << "\n"
                                 << coordinator->log();
    }
    coordinator->process().signal(SIGKILL);
    EXPECT_EQ(coordinator->process().wait(seconds(10)), 128 + SIGKILL);
    coordinator = std::make_unique<CoordinatorProcess>(scratch.path(), 2.0, port,
                                                       "coordinator" + std::to_string(kill));
    ASSERT_TRUE(coordinator->ok()) << coordinator->log();
    observe("across restart " + std::to_string(kill));
    EXPECT_NE(coordinator->log().find(std::to_string(jobs.size()) + " job(s) remembered"),
              std::string::npos)
        << coordinator->log();
  }
  ASSERT_LT(seen[0], int64_t(64) * 48 * 1024) << "the job ended before the last kill";

  for (size_t j = 0; j < jobs.size(); ++j) {
    const std::string out = scratch / ("distributed" + std::to_string(j) + ".exr");
    CommandResult fetched = runCommand(
        {FARM_CLI_BIN, "fetch", "--coordinator", address, jobs[j], "-o", out, "--timeout", "240"},
        seconds(250), scratch.path());
    ASSERT_EQ(fetched.exitCode, 0) << fetched.err << "\n" << coordinator->log();
  }
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(workers[size_t(i)]->stop(seconds(20)), 0) << "worker " << i;
    const std::string log = readFile(scratch / ("worker" + std::to_string(i) + ".log"));
    size_t registrations = 0;
    for (size_t at = log.find("registered"); at != std::string::npos;
         at = log.find("registered", at + 1)) {
      ++registrations;
    }
    EXPECT_GE(registrations, 2u) << "worker " << i << " never reconnected:\n" << log;
  }
  for (size_t j = 0; j < jobs.size(); ++j) {
    std::vector<std::string> render = {
        FARM_CLI_BIN, "render", kScene, "-o", scratch / ("embedded" + std::to_string(j) + ".exr"),
        "--threads",  "2"};
    render.insert(render.end(), jobSettings[j].begin(), jobSettings[j].end());
    CommandResult rendered = runCommand(render, seconds(120), scratch.path());
    ASSERT_EQ(rendered.exitCode, 0) << rendered.err;
    Image distributed, embedded;
    std::string error;
    ASSERT_TRUE(
        readExr(scratch / ("distributed" + std::to_string(j) + ".exr"), &distributed, &error))
        << error;
    ASSERT_TRUE(readExr(scratch / ("embedded" + std::to_string(j) + ".exr"), &embedded, &error))
        << error;
    SCOPED_TRACE("job " + std::to_string(j));
    expectImagesAgree(distributed, embedded);
  }
  EXPECT_EQ(coordinator->process().stop(), 0);
}

// `farm render --bootstrap-candidates`: a count the user gives is the count drawn, the default
// sizes the bootstrap to the job (a small one gets the pilot's floor), and a count out of range is
// a clear error.
TEST(FarmRender, BootstrapCandidatesOption) {
  ScratchDir scratch("bootstrap-option");
  ASSERT_FALSE(scratch.path().empty());
  auto render = [&](std::vector<std::string> extra) {
    std::vector<std::string> argv = {
        FARM_CLI_BIN, "render",    kScene,     "-o",          scratch / "b.exr",
        "--width",    "32",        "--height", "32",          "--mpp",
        "4",          "--threads", "2",        "--algorithm", "pssmlt"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return runCommand(argv, seconds(120), scratch.path());
  };
  CommandResult given = render({"--bootstrap-candidates", "5000"});
  ASSERT_EQ(given.exitCode, 0) << given.err;
  EXPECT_NE(given.out.find("from 5000 candidates"), std::string::npos) << given.out;
  CommandResult sized = render({});
  ASSERT_EQ(sized.exitCode, 0) << sized.err;
  EXPECT_NE(sized.out.find("from 1024 candidates"), std::string::npos) << sized.out;
  for (const char* bad : {"-1", "100000000000"}) {
    CommandResult refused = render({"--bootstrap-candidates", bad});
    EXPECT_NE(refused.exitCode, 0) << bad;
    EXPECT_NE(refused.err.find("--bootstrap-candidates must be in 0..67108864"), std::string::npos)
        << bad << ": " << refused.err;
  }
}

// `farm render` and `farm submit` render with auto unless told otherwise: the plan's first
// candidate, pt on the Cornell box (the corpus's measuring half, docs/corpus.md, is what made it
// the default).
TEST(FarmRender, AutoIsTheDefaultAlgorithm) {
  ScratchDir scratch("default-algorithm");
  ASSERT_FALSE(scratch.path().empty());
  CommandResult r = runCommand({FARM_CLI_BIN, "render", kScene, "-o", scratch / "d.exr", "--width",
                                "16", "--height", "16", "--spp", "2", "--threads", "2"},
                               seconds(120), scratch.path());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("algorithm: pt (auto)"), std::string::npos) << r.out;
  CommandResult help = runCommand({FARM_CLI_BIN, "submit", "--help"}, seconds(30), scratch.path());
  EXPECT_NE(help.out.find("--algorithm TEXT=auto"), std::string::npos) << help.out;
}

// `farm render --max-depth`: the longest path in edges overrides the scene file's (65 on the
// Cornell box), the image's metadata and the report say so, 2 edges leave only direct light (a
// darker image), and a depth out of range is a clear error.
TEST(FarmRender, MaxDepthOption) {
  ScratchDir scratch("max-depth-option");
  ASSERT_FALSE(scratch.path().empty());
  auto render = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> argv = {FARM_CLI_BIN, "render", kScene,     "-o",        scratch / out,
                                     "--width",    "32",     "--height", "32",        "--algorithm",
                                     "pt",         "--spp",  "16",       "--threads", "2"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return runCommand(argv, seconds(120), scratch.path());
  };
  CommandResult file = render("file.exr", {});
  ASSERT_EQ(file.exitCode, 0) << file.err;
  EXPECT_EQ(file.out.find("--max-depth"), std::string::npos) << file.out;
  CommandResult direct = render("direct.exr", {"--max-depth", "2"});
  ASSERT_EQ(direct.exitCode, 0) << direct.err;
  EXPECT_NE(direct.out.find("paths of at most 2 edges (--max-depth)"), std::string::npos)
      << direct.out;
  Image a, b;
  ImageMetadata ma, mb;
  std::string error;
  ASSERT_TRUE(readExr(scratch / "file.exr", &a, &error, &ma)) << error;
  ASSERT_TRUE(readExr(scratch / "direct.exr", &b, &error, &mb)) << error;
  EXPECT_EQ(ma.at("farm:maxDepth"), "65");
  EXPECT_EQ(mb.at("farm:maxDepth"), "2");
  double sumFile = 0, sumDirect = 0;
  for (float v : a.rgb) sumFile += v;
  for (float v : b.rgb) sumDirect += v;
  // Direct light alone was 72% of the Cornell box's image (measured at these settings); 16
  // samples a pixel over 1024 pixels put each image's mean within a few percent, far inside the
  // 13 points between 72% and this bound.
  EXPECT_LT(sumDirect, 0.85 * sumFile);
  for (const char* bad : {"-2", "4097"}) {
    CommandResult refused = render("bad.exr", {"--max-depth", bad});
    EXPECT_NE(refused.exitCode, 0) << bad;
    EXPECT_NE(refused.err.find("--max-depth must be -1 (unbounded), 0 (the scene's) or 1..4096"),
              std::string::npos)
        << bad << ": " << refused.err;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Algorithms, ClusterTest,
    ::testing::Values(
        ClusterCase{"pt", {"--spp", "64"}}, ClusterCase{"bdpt", {"--spp", "16"}},
        withPixelAllocation({"bdpt", {"--spp", "16"}, kScene, "bdpt_pixel_allocation"}),
        ClusterCase{"pssmlt", {"--mpp", "32"}}, ClusterCase{"pssmlt-pt", {"--mpp", "32"}},
        ClusterCase{"mmlt", {"--mpp", "32"}}, ClusterCase{"mlt", {"--mpp", "32"}},
        // Kelemen's combination of the large steps: a setting and a weight per
        // chain, both of which must reach the workers
        ClusterCase{
            "mmlt", {"--mpp", "32", "--combine-large-steps"}, kScene, "mmlt_combined_large_steps"},
        ClusterCase{"erpt", {"--spp", "4"}},
        // pbrt-v3, PLY meshes and PNG textures (with a space
        // in a file name) through the bundle upload
        ClusterCase{"pssmlt",
                    {"--mpp", "8"},
                    std::string(FARM_SHARED_DIR) + "/scenes/veach-ajar/scene.pbrt",
                    "pssmlt_veach_ajar_pbrt"},
        // a shading-normal convention other than the scene file's: the workers
        // must load the scene with it, as the embedded render does
        ClusterCase{"pt",
                    {"--spp", "8", "--shading-normals", "lax"},
                    std::string(FARM_SHARED_DIR) + "/scenes/water-caustic/scene.xml",
                    "pt_water_caustic_lax"},
        // participating media, the smoke's grid file through the bundle upload
        ClusterCase{"bdpt",
                    {"--spp", "4"},
                    std::string(FARM_TEST_DATA_DIR) + "/smoky-box/scene.xml",
                    "bdpt_smoky_box_media"}),
    [](const auto& info) {
      std::string name = info.param.name.empty() ? info.param.algorithm : info.param.name;
      std::replace(name.begin(), name.end(), '-', '_');
      return name;
    });

INSTANTIATE_TEST_SUITE_P(
    Algorithms, ClusterFailure,
    ::testing::Values(ClusterCase{"pt", {"--spp", "256"}}, ClusterCase{"mlt", {"--mpp", "256"}},
                      ClusterCase{"erpt", {"--spp", "8"}},
                      // chains through media (ratio tracking's numbers too) resume exactly
                      ClusterCase{"mmlt",
                                  {"--mpp", "128"},
                                  std::string(FARM_TEST_DATA_DIR) + "/smoky-box/scene.xml",
                                  "mmlt_smoky_box_media"},
                      // pseudo-marginal path-space chains through a grid of smoke: their
                      // estimate count travels to the workers, their states keep f's estimate
                      ClusterCase{"mlt",
                                  {"--mpp", "64", "--medium-samples", "2"},
                                  std::string(FARM_TEST_DATA_DIR) + "/smoke-room/scene.xml",
                                  "mlt_smoke_room_pseudo_marginal"}),
    [](const auto& info) {
      return info.param.name.empty() ? info.param.algorithm : info.param.name;
    });

}  // namespace
}  // namespace farm::testing
