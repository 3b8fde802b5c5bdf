// farm: render a scene in one process, or submit it to a farm-coordinator and follow the job.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <thread>

#include "cli/compare.h"
#include "cli/embedded_render.h"
#include "cli/farm_client.h"
#include "cli/render_report.h"
#include "common/film/image.h"
#include "common/plan/scene_analysis.h"
#include "common/render/algorithm_pilot.h"
#include "common/scene/scene.h"
#include "ops/client_security_options.h"

namespace {

namespace fs = std::filesystem;
using farm::Status;

constexpr int kUsageError = 2;
constexpr int kFailure = 1;

int fail(const std::string& message, int code = kFailure) {
  std::cerr << "farm: error: " << message << "\n";
  return code;
}

std::atomic<bool> gInterrupted{false};
extern "C" void onInterrupt(int) {
  gInterrupted = true;
}

// Ctrl-C and SIGTERM set the flag this returns, for a command to end cleanly.
const std::atomic<bool>* catchInterrupts() {
  std::signal(SIGINT, onInterrupt);
  std::signal(SIGTERM, onInterrupt);
  return &gInterrupted;
}

// --- Render options shared by `render` and `submit`

struct RenderOptions {
  std::string algorithm = "auto";
  int64_t spp = 16, mpp = 16;
  double time = 0;
  int width = 0, height = 0;
  std::string seed = "1";  // parsed by hand: CLI11 would wrap "-1" around to 2^64 - 1
  std::string reference;
  float largeStep = farm::RenderSettings().largeStepProbability;
  std::string mutationMix;
  double erptChains = farm::RenderSettings().erptChains;
  int erptLength = farm::RenderSettings().erptLength;
  int mediumSamples = farm::RenderSettings().mediumSamples;
  int mediumMarch = farm::RenderSettings().mediumMarchSteps;
  int chains = 0;
  int64_t bootstrapCandidates = 0;
  int64_t flushEvery = 0;
  double untilError = 0;
  int errorGroups = 0;
  bool noPlan = false;
  bool pilot = false;
  bool combineLargeSteps = false;
  std::string pixelAllocation;
  std::string shadingNormals = "scene";
  int maxDepth = 0;
  CLI::Option *timeOption = nullptr, *widthOption = nullptr, *heightOption = nullptr;
};

void addRenderOptions(CLI::App* command, RenderOptions* o) {
  command
      ->add_option("--algorithm", o->algorithm,
                   "pt (path tracing), bdpt (bidirectional), pssmlt (primary-sample MLT over "
                   "bdpt), pssmlt-pt (the same over pt), mmlt (multiplexed MLT), mlt (path-space "
                   "MLT with Veach's mutations), erpt (energy redistribution path tracing), "
                   "auto (the scene's plan picks one, its first candidate: `farm plan SCENE` "
                   "shows how and why; with --pilot a short render of each candidate ranks "
                   "them; where the pick is bdpt and --time is given, a pilot of a tenth of it "
                   "places bdpt's samples where its error is; docs/corpus.md)")
      ->default_str("auto");
  command->add_option("--spp", o->spp, "samples per pixel (pt, bdpt), seeds per pixel (erpt)")
      ->default_str("16");
  command->add_option("--mpp", o->mpp, "mutations per pixel (pssmlt, pssmlt-pt, mmlt, mlt)")
      ->default_str("16");
  command
      ->add_option("--large-step", o->largeStep,
                   "probability of a large step, a fresh independent sample (pssmlt, pssmlt-pt, "
                   "mmlt; Kelemen et al. 2002)")
      ->default_str(std::to_string(o->largeStep).substr(0, 3));
  command->add_flag("--combine-large-steps", o->combineLargeSteps,
                    "pssmlt, pssmlt-pt, mmlt: count each large step's proposal also as an "
                    "independent sample, weighted against the chain by multiple importance "
                    "sampling (Kelemen et al. 2002, 4.1); Z is then the bootstrap's alone");
  command->add_option("--pixel-allocation", o->pixelAllocation,
                      "pt, bdpt: FILE of where the samples land and which of the two estimators "
                      "takes each cell of the film (common/film/pixel_allocation.h's byte form, "
                      "as tools/pixel_allocation.py writes it from a pilot's images; "
                      "docs/corpus.md); its film must be the job's");
  command
      ->add_option("--mutation-mix", o->mutationMix,
                   "mlt: relative weights of Veach's mutations, normalized over those that apply "
                   "to the current path: bidir (bidirectional), lens-subpath, lens (lens "
                   "perturbation), caustic, multichain, manifold (manifold exploration: the lens "
                   "perturbation with a manifold walk through the specular chain below); names "
                   "left out keep their defaults")
      ->default_str(farm::formatMutationMix(farm::MutationMix()));
  command
      ->add_option("--erpt-chains", o->erptChains,
                   "erpt: chains a seed path starts on average (Cline et al. 2005); its energy "
                   "is spread in deposits of Z / (chains * length)")
      ->default_str("1");
  command->add_option("--erpt-length", o->erptLength, "erpt: mutations per chain")
      ->default_str("100");
  command
      ->add_option("--medium-samples", o->mediumSamples,
                   "mlt and erpt through density grids: ratio-tracking estimates averaged into "
                   "each transmittance of f (pseudo-marginal MLT: exact for any count; more "
                   "give fewer rejections at their cost)")
      ->default_str("1");
  command
      ->add_option(
          "--medium-march", o->mediumMarch,
          "mlt and erpt through density grids: march each transmittance with this many steps "
          "instead (deterministic, biased by the step); 0: estimate")
      ->default_str("0");
  command
      ->add_option("--chains", o->chains,
                   "independent Markov chains (pssmlt, pssmlt-pt, mmlt, mlt), each seeded by the "
                   "bootstrap, or work units (pt, bdpt): more chains cover the image more evenly "
                   "where chains hardly leave the kind of path they start on; 0: the plan's, 64 "
                   "or, for the Markov chains where any light arrives along "
                   "specular-diffuse-specular paths, 1024 (`farm plan` says which)")
      ->default_str("0");
  command
      ->add_option("--bootstrap-candidates", o->bootstrapCandidates,
                   "candidate paths of the bootstrap that estimates Z and draws the chains' seeds "
                   "(pssmlt, pssmlt-pt, mmlt, mlt, erpt); 0 sizes it to the job: about 5% of its "
                   "work, more where Z's standard error would show beside an average pixel's")
      ->default_str("0");
  command
      ->add_option("--flush-every", o->flushEvery,
                   "mutations (or samples) a chain runs between flushes to the coordinator; 0: "
                   "one film's worth (the pixel count, within 4096 .. 2^20). Longer: fewer, "
                   "denser uploads for a coordinator with many workers, and more work lost with "
                   "a worker that dies")
      ->default_str("0");
  command
      ->add_option("--until-error", o->untilError,
                   "stop once the image's relative MSE, estimated without a reference from the "
                   "spread between independent groups of chains, is at most this (or at the "
                   "budget, --spp/--mpp/--time, whichever comes first); 0: render the whole "
                   "budget")
      ->default_str("0");
  command
      ->add_option("--error-groups", o->errorGroups,
                   "independent groups of chains whose spread estimates the error without a "
                   "reference (at most the chain count; erpt: the seeds per pixel); the "
                   "coordinator keeps a film for each. 1: no estimate, one film; 0: " +
                       std::to_string(farm::kErrorGroups))
      ->default_str("0");
  command->add_flag("--pilot", o->pilot,
                    "with --algorithm auto: a pilot of each of the plan's candidates, 10% of "
                    "--time in all or 1 s each, ranks them by estimated error x time, and one "
                    "under half the first's renders (off by default: on the corpus it cost "
                    "more than it saved, docs/corpus.md)");
  command->add_flag(
      "--no-plan", o->noPlan,
      "keep every part the settings name, even those the scene's plan leaves out (mlt's "
      "caustic, multi-chain and manifold perturbations on a scene without specular surfaces): "
      "to measure what leaving them out saves");
  command
      ->add_option("--shading-normals", o->shadingNormals,
                   "scene (the file's: a Mitsuba integrator's strictNormals, false when it has "
                   "none; strict for pbrt files), strict (drop paths whose directions the "
                   "geometric and the shading normal put on different sides of a surface: no "
                   "light leaks through smooth-shaded meshes, but their silhouettes lose the "
                   "light of such paths) or lax (keep them, as Mitsuba without strictNormals, "
                   "pbrt-v4 and Tungsten do)")
      ->default_str("scene");
  command
      ->add_option("--max-depth", o->maxDepth,
                   "longest path in edges (2: direct light only; Mitsuba's maxDepth, which "
                   "Tungsten's max_bounces equals): 0 the scene file's (unbounded where it "
                   "names none), -1 unbounded, at most 4096")
      ->default_str("0");
  o->timeOption = command->add_option(
      "--time", o->time,
      "wall-clock budget in seconds, counted from the job's start (bootstrap included): "
      "render until it is spent instead of to --spp/--mpp");
  o->widthOption = command->add_option(
      "--width", o->width, "film width in pixels (default: the scene's; keeps the field of view)");
  o->heightOption = command->add_option(
      "--height", o->height,
      "film height in pixels (default: the scene's, or the width's aspect ratio)");
  command->add_option("--seed", o->seed, "random seed: same seed and settings, same image")
      ->type_name("UINT")
      ->default_str("1");
  command->add_option("--reference", o->reference,
                      "reference EXR of the same size: progress and report show RMSE and "
                      "relative MSE against it");
}

// --shading-normals, shared by the render options and `farm plan`; false with *error otherwise.
bool parseShadingNormalsOption(const std::string& value, farm::ShadingNormals* out,
                               std::string* error) {
  if (farm::parseShadingNormals(value, out)) return true;
  *error = "--shading-normals must be scene, strict or lax, not '" + value + "'";
  return false;
}

// Checks the option values with the user's names for them; false with *error otherwise.
bool toSettings(const RenderOptions& o, farm::RenderSettings* s, std::string* error) {
  s->autoAlgorithm = o.algorithm == "auto";
  if (!s->autoAlgorithm && !farm::parseAlgorithm(o.algorithm, &s->algorithm)) {
    *error = std::string("--algorithm must be ") + farm::algorithmList() + " or auto, not '" +
             o.algorithm + "'";
    return false;
  }
  s->ignorePlan = o.noPlan;
  s->pilot = o.pilot;
  if (!parseShadingNormalsOption(o.shadingNormals, &s->shadingNormals, error)) return false;
  constexpr int64_t kMaxPerPixel = int64_t(1) << 24;
  if (o.spp < 1 || o.spp > kMaxPerPixel) {
    *error = "--spp must be between 1 and " + std::to_string(kMaxPerPixel) + ", not " +
             std::to_string(o.spp);
    return false;
  }
  if (o.mpp < 1 || o.mpp > kMaxPerPixel) {
    *error = "--mpp must be between 1 and " + std::to_string(kMaxPerPixel) + ", not " +
             std::to_string(o.mpp);
    return false;
  }
  if (o.timeOption->count() && !(std::isfinite(o.time) && o.time > 0)) {
    *error = "--time must be a finite number of seconds > 0";
    return false;
  }
  for (auto [option, value, name] : {std::tuple{o.widthOption, o.width, "--width"},
                                     std::tuple{o.heightOption, o.height, "--height"}}) {
    if (option->count() && (value < 1 || value > 65536)) {
      *error =
          std::string(name) + " must be between 1 and 65536 pixels, not " + std::to_string(value);
      return false;
    }
  }
  s->largeStepProbability = o.largeStep;
  s->combineLargeSteps = o.combineLargeSteps;
  if (!o.pixelAllocation.empty()) {
    std::ifstream in(o.pixelAllocation, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in && !in.eof()) {
      *error = "--pixel-allocation: cannot read " + o.pixelAllocation;
      return false;
    }
    try {
      s->pixelAllocation =
          std::make_shared<const farm::PixelAllocation>(farm::PixelAllocation::decode(bytes));
    } catch (const std::invalid_argument& e) {
      *error = "--pixel-allocation " + o.pixelAllocation + ": " + e.what();
      return false;
    }
  }
  s->erptChains = o.erptChains;
  s->erptLength = o.erptLength;
  s->mediumSamples = o.mediumSamples;
  s->mediumMarchSteps = o.mediumMarch;
  if (o.chains < 0 || o.chains > (1 << 20)) {
    *error = "--chains must be between 0 (the plan's) and 1048576, not " + std::to_string(o.chains);
    return false;
  }
  s->numChains = o.chains;
  s->bootstrapSamples = o.bootstrapCandidates;
  s->flushInterval = o.flushEvery;
  s->untilError = o.untilError;
  s->errorGroups = o.errorGroups;
  if (!farm::parseMutationMix(o.mutationMix, &s->mutationMix, error)) {
    *error = "--mutation-mix: " + *error;
    return false;
  }
  s->samplesPerPixel = o.spp;
  s->mutationsPerPixel = o.mpp;
  s->timeBudgetSeconds = o.timeOption->count() ? o.time : 0;
  s->width = o.width;
  s->height = o.height;
  const bool digitsOnly = !o.seed.empty() && o.seed.size() <= 20 &&
                          o.seed.find_first_not_of("0123456789") == std::string::npos;
  errno = 0;
  const unsigned long long seed = digitsOnly ? std::strtoull(o.seed.c_str(), nullptr, 10) : 0;
  if (!digitsOnly || errno == ERANGE) {
    *error = "--seed must be a whole number between 0 and 2^64 - 1, not '" + o.seed + "'";
    return false;
  }
  s->seed = seed;
  s->maxDepth = o.maxDepth;
  std::string problem = s->validate();
  if (!problem.empty()) {
    *error = problem;
    return false;
  }
  if (!o.reference.empty() && !fs::is_regular_file(o.reference)) {
    *error = "reference image '" + o.reference + "' does not exist";
    return false;
  }
  return true;
}

std::string previewPath(const std::string& exrPath) {
  fs::path p(exrPath);
  p.replace_extension(".png");
  return p.string();
}

bool checkOutputPath(const std::string& path, std::string* error) {
  fs::path parent = fs::absolute(path).parent_path();
  if (!fs::is_directory(parent)) {
    *error = "cannot write '" + path + "': directory '" + parent.string() + "' does not exist";
    return false;
  }
  if (access(parent.c_str(), W_OK) != 0) {
    *error = "cannot write '" + path + "': directory '" + parent.string() + "' is not writable";
    return false;
  }
  return true;
}

// Draws progress on stderr: in place on a terminal, every few seconds otherwise (logs).
class ProgressDisplay {
 public:
  ProgressDisplay() : tty_(isatty(STDERR_FILENO)) {}
  void show(const farm::JobProgress& p) {
    if (!p.errorSeries.empty()) lastError_ = p.errorSeries.back();
    farm::JobProgress shown = p;
    if (shown.errorSeries.empty() && lastError_) shown.errorSeries.push_back(*lastError_);
    const auto now = std::chrono::steady_clock::now();
    if (tty_) {
      std::cerr << "\r" << farm::progressLine(shown) << "\033[K" << std::flush;
      drawn_ = true;
    } else if (now - lastLine_ > std::chrono::seconds(5) || p.phase == farm::JobPhase::kDone) {
      std::cerr << farm::progressLine(shown) << "\n";
      lastLine_ = now;
    }
  }
  void finish() {
    if (tty_ && drawn_) std::cerr << "\n";
    drawn_ = false;
  }

 private:
  bool tty_;
  bool drawn_ = false;
  std::optional<farm::ErrorSample> lastError_;
  std::chrono::steady_clock::time_point lastLine_{};
};

// --- Subcommands

int runRender(const std::string& scene, const std::string& output, const RenderOptions& options,
              int threads, int workers, const std::string& reportDir) {
  farm::EmbeddedRenderOptions render;
  std::string error;
  if (!toSettings(options, &render.settings, &error)) return fail(error, kUsageError);
  if (!fs::is_regular_file(scene)) return fail("scene file '" + scene + "' does not exist");
  if (!checkOutputPath(output, &error)) return fail(error, kUsageError);
  if (workers > threads) {
    return fail("--workers (" + std::to_string(workers) + ") must not exceed --threads (" +
                    std::to_string(threads) + ")",
                kUsageError);
  }
  if (!reportDir.empty()) {
    std::error_code ec;
    fs::create_directories(reportDir, ec);
    if (ec) return fail("cannot create report directory '" + reportDir + "': " + ec.message());
  }
  render.scenePath = scene;
  render.referencePath = options.reference;
  render.threads = threads;
  render.workers = workers;
  ProgressDisplay display;
  render.onProgress = [&](const farm::JobProgress& p) { display.show(p); };
  render.interrupted = catchInterrupts();

  farm::EmbeddedRenderResult result;
  Status status = farm::renderEmbedded(render, &result);
  display.finish();
  if (!status.isOk()) return fail(status.message());

  if (!farm::writeExr(output, result.image, result.metadata, &error)) return fail(error);
  const std::string png = previewPath(output);
  if (!farm::writePreview(png, result.image, &error)) return fail(error);
  std::cout << farm::finalReport(result.progress, scene, options.reference);
  std::cout << "  wrote " << output << " and " << png << "\n";
  if (!reportDir.empty()) {
    if (!farm::writeReportDir(reportDir, result.progress, scene, output, options.reference,
                              &error)) {
      return fail(error);
    }
    std::cout << "  wrote " << (fs::path(reportDir) / "error_vs_time.csv").string() << " and "
              << (fs::path(reportDir) / "report.json").string() << "\n";
  }
  return 0;
}

int connectTo(farm::FarmClient& client) {
  Status s = client.connect(5);
  if (!s.isOk()) return fail(s.message());
  return 0;
}

int runSubmit(const std::string& address, const farm::ClientSecurity& security,
              const std::string& scene, const RenderOptions& options) {
  farm::Submission submission;
  std::string error;
  if (!toSettings(options, &submission.settings, &error)) return fail(error, kUsageError);
  if (!fs::is_regular_file(scene)) return fail("scene file '" + scene + "' does not exist");
  if (!farm::collectSceneBundle(scene, &submission.bundle, &error,
                                [](const std::string& w) { std::cerr << "farm: " << w << "\n"; })) {
    return fail(error);
  }
  submission.referencePath = options.reference;
  submission.name = fs::path(scene).filename().string();
  farm::FarmClient client(address, security);
  if (int rc = connectTo(client)) return rc;
  std::string jobId;
  farm::SubmitStats stats;
  Status s = client.submit(submission, &jobId, &stats);
  if (!s.isOk()) return fail(s.message());
  std::cerr << "farm: uploaded " << stats.filesUploaded << " of " << stats.filesTotal << " files ("
            << stats.bytesUploaded << " bytes; the rest were on the coordinator)\n";
  std::cout << jobId << std::endl;  // the last line of stdout: scripts read it
  return 0;
}

// Progress with the latest error sample only (the whole series can be long).
Status latestProgress(farm::FarmClient& client, const std::string& job, farm::JobProgress* p) {
  Status s = client.progress(job, UINT32_MAX, p);
  if (s.isOk() && p->errorSeriesTotal > 0) s = client.progress(job, p->errorSeriesTotal - 1, p);
  return s;
}

int runStatus(const std::string& address, const farm::ClientSecurity& security,
              const std::string& job, bool json) {
  farm::FarmClient client(address, security);
  if (int rc = connectTo(client)) return rc;
  farm::JobProgress p;
  Status s = latestProgress(client, job, &p);
  if (!s.isOk()) return fail(s.message());
  if (json) {
    std::cout << farm::progressJson(p).dump(2) << "\n";
  } else {
    std::cout << farm::statusText(p);
  }
  return 0;
}

int runFetch(const std::string& address, const farm::ClientSecurity& security,
             const std::string& job, const std::string& output, double timeout) {
  std::string error;
  if (!checkOutputPath(output, &error)) return fail(error, kUsageError);
  farm::FarmClient client(address, security);
  if (int rc = connectTo(client)) return rc;
  catchInterrupts();
  const auto start = std::chrono::steady_clock::now();
  ProgressDisplay display;
  farm::JobProgress p;
  for (;;) {
    Status s = latestProgress(client, job, &p);
    if (!s.isOk()) {
      display.finish();
      return fail(s.message());
    }
    display.show(p);
    if (farm::isTerminal(p.phase)) break;
    if (gInterrupted) {
      display.finish();
      return fail("interrupted (the job goes on; fetch it later)");
    }
    if (timeout > 0 &&
        std::chrono::steady_clock::now() - start > std::chrono::duration<double>(timeout)) {
      display.finish();
      return fail("job " + job + " is still " + farm::jobPhaseName(p.phase) + " after " +
                  std::to_string(int(timeout)) + " s");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }
  display.finish();
  if (p.phase == farm::JobPhase::kFailed) return fail("job " + job + " failed: " + p.error);
  if (p.phase == farm::JobPhase::kCancelled) return fail("job " + job + " was cancelled");
  Status s = client.fetchImage(job, false, output);
  if (!s.isOk()) return fail(s.message());
  farm::Image image;
  if (!farm::readExr(output, &image, &error)) return fail(error);
  const std::string png = previewPath(output);
  if (!farm::writePreview(png, image, &error)) return fail(error);
  std::cout << farm::finalReport(p, p.name, p.hasReference ? "the reference" : "");
  std::cout << "  wrote " << output << " and " << png << "\n";
  return 0;
}

// Follows a job as the coordinator streams it (WatchJob), until it ends or Ctrl-C.
int runWatch(const std::string& address, const farm::ClientSecurity& security,
             const std::string& job, double interval) {
  farm::FarmClient client(address, security);
  if (int rc = connectTo(client)) return rc;
  const std::atomic<bool>* interrupted = catchInterrupts();
  ProgressDisplay display;
  farm::JobProgress last;
  bool any = false;
  Status s = client.watch(job, interval, [&](const farm::JobProgress& p) {
    display.show(p);
    last = p;
    any = true;
    return !*interrupted;
  });
  display.finish();
  if (!s.isOk()) return fail(s.message());
  if (*interrupted) return fail("interrupted (the job goes on)");
  if (!any) return fail("the coordinator sent no progress for job " + job);
  if (last.phase == farm::JobPhase::kFailed) return fail("job " + job + " failed: " + last.error);
  if (last.phase == farm::JobPhase::kCancelled) return fail("job " + job + " was cancelled");
  std::cout << "job " << job << ": " << farm::jobPhaseName(last.phase) << " after "
            << farm::formatDuration(last.elapsedSeconds) << " (fetch it with `farm fetch`)\n";
  return 0;
}

int runCancel(const std::string& address, const farm::ClientSecurity& security,
              const std::string& job) {
  farm::FarmClient client(address, security);
  if (int rc = connectTo(client)) return rc;
  farm::JobPhase phase;
  Status s = client.cancel(job, &phase);
  if (!s.isOk()) return fail(s.message());
  std::cout << "job " << job << ": " << farm::jobPhaseName(phase) << "\n";
  return 0;
}

int runList(const std::string& address, const farm::ClientSecurity& security) {
  farm::FarmClient client(address, security);
  if (int rc = connectTo(client)) return rc;
  std::vector<farm::JobProgress> jobs;
  Status s = client.list(&jobs);
  if (!s.isOk()) return fail(s.message());
  if (jobs.empty()) std::cout << "no jobs\n";
  for (const farm::JobProgress& j : jobs) {
    char line[512];
    std::snprintf(line, sizeof(line), "%-20s %-14s %6.1f%%  %-7s %9s  %s", j.jobId.c_str(),
                  farm::jobPhaseName(j.phase), 100 * j.fraction,
                  farm::algorithmName(j.settings.algorithm),
                  farm::formatDuration(j.elapsedSeconds).c_str(), j.name.c_str());
    std::cout << line;
    if (!j.error.empty()) std::cout << "  (" << j.error << ")";
    std::cout << "\n";
  }
  return 0;
}

int runCompareCommand(const std::string& scene, const std::string& algorithms,
                      const RenderOptions& options, const std::string& coordinator,
                      const farm::ClientSecurity& security, int threads,
                      const std::string& reportDir) {
  farm::CompareOptions compare;
  std::string error;
  // --pilot goes to auto's job alone (runCompare), so the shared settings check it not.
  RenderOptions shared = options;
  shared.pilot = false;
  if (!toSettings(shared, &compare.settings, &error)) return fail(error, kUsageError);
  if (!farm::parseAlgorithms(algorithms, &compare.algorithms, &error))
    return fail(error, kUsageError);
  compare.settings.pilot = options.pilot;
  if (options.pilot && std::none_of(compare.algorithms.begin(), compare.algorithms.end(),
                                    [](const farm::AlgorithmChoice& c) { return c.automatic; }))
    return fail("--pilot ranks auto's candidates: --algorithms names no auto", kUsageError);
  if (!fs::is_regular_file(scene)) return fail("scene file '" + scene + "' does not exist");
  if (!options.reference.empty() && !fs::is_regular_file(options.reference))
    return fail("reference '" + options.reference + "' does not exist");
  compare.scene = scene;
  compare.reference = options.reference;
  compare.reportDir = reportDir;
  compare.coordinator = coordinator;
  compare.security = security;
  compare.threads = threads;
  ProgressDisplay display;
  std::string current;
  compare.onProgress = [&](const std::string& name, const farm::JobProgress& p) {
    if (name != current) {
      display.finish();
      std::cerr << "farm compare: " << name << "\n";
      current = name;
    }
    display.show(p);
  };
  compare.interrupted = catchInterrupts();
  farm::CompareResult result;
  Status s = farm::runCompare(compare, &result);
  display.finish();
  if (!s.isOk()) return fail(s.message());
  for (const farm::ReportEntry& e : result.entries) {
    std::cout << farm::finalReport(e.progress, scene, options.reference);
  }
  if (!result.warning.empty()) std::cerr << "farm: warning: " << result.warning << "\n";
  std::cout << "  wrote " << (fs::path(reportDir) / "index.html").string() << "\n";
  return 0;
}

int runPlan(const std::string& scenePath, const std::string& algorithm,
            const std::string& mutationMix, const std::string& shadingNormals, double time,
            int width, int height, bool pilot, bool json) {
  farm::RenderSettings settings;
  std::string error;
  if (!parseShadingNormalsOption(shadingNormals, &settings.shadingNormals, &error))
    return fail(error, kUsageError);
  settings.autoAlgorithm = algorithm == "auto";
  if (!settings.autoAlgorithm && !farm::parseAlgorithm(algorithm, &settings.algorithm)) {
    return fail(std::string("--algorithm must be ") + farm::algorithmList() + " or auto, not '" +
                    algorithm + "'",
                kUsageError);
  }
  if (!farm::parseMutationMix(mutationMix, &settings.mutationMix, &error))
    return fail("--mutation-mix: " + error, kUsageError);
  if (!(std::isfinite(time) && time >= 0)) return fail("--time must be >= 0 seconds", kUsageError);
  settings.timeBudgetSeconds = time;
  settings.width = width;
  settings.height = height;
  settings.pilot = pilot;
  if (std::string problem = settings.validate(); !problem.empty())
    return fail(problem, kUsageError);
  if (!fs::is_regular_file(scenePath)) return fail("scene file '" + scenePath + "' does not exist");
  farm::RenderPlan plan;
  try {
    std::shared_ptr<farm::Scene> scene = farm::loadScene(scenePath, settings);
    if (pilot) {
      plan = farm::planJob(scene, &settings);
    } else {
      plan = farm::planRender(farm::analyseScene(*scene), settings.algorithm,
                              settings.autoAlgorithm, settings.mutationMix, settings.numChains);
    }
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  const std::vector<std::string> lines = plan.describe();
  if (json) {
    nlohmann::json j;
    j["scene"] = scenePath;
    j["algorithm"] = farm::algorithmName(plan.algorithm);
    j["automatic"] = plan.automatic;
    std::vector<std::string> candidates;
    for (farm::Algorithm a : plan.shortlist) candidates.push_back(farm::algorithmName(a));
    j["candidates"] = candidates;
    j["mutation_mix"] = farm::formatMutationMix(plan.mutationMix);
    nlohmann::json parts = nlohmann::json::array();
    for (const farm::PlanPart& p : plan.parts)
      parts.push_back({{"name", p.name}, {"enabled", p.enabled}, {"reason", p.reason}});
    j["parts"] = parts;
    nlohmann::json figures = nlohmann::json::array();
    for (const farm::PilotFigure& f : plan.pilot) {
      figures.push_back({{"algorithm", farm::algorithmName(f.algorithm)},
                         {"seconds", f.seconds},
                         {"bootstrap_seconds", f.bootstrapSeconds},
                         {"estimated_relmse", f.estimatedRelMse},
                         {"score", f.score},
                         {"failure", f.failure}});
    }
    j["pilot"] = figures;
    j["lines"] = lines;
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  std::cout << "plan for " << scenePath << ":\n";
  for (const std::string& line : lines) std::cout << "  " << line << "\n";
  return 0;
}

int runReportCommand(const std::string& coordinator, const farm::ClientSecurity& security,
                     const std::string& job, const std::string& reportDir) {
  farm::CompareResult result;
  Status s = farm::runJobReport(coordinator, security, job, reportDir, &result);
  if (!s.isOk()) return fail(s.message());
  if (!result.warning.empty()) std::cerr << "farm: warning: " << result.warning << "\n";
  std::cout << "wrote " << (fs::path(reportDir) / "index.html").string() << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "farm: a Metropolis light transport render farm. Render a scene in this process "
      "(render), compare algorithms on it (compare), or submit it to a farm-coordinator and "
      "follow the job (submit, status, watch, fetch, report, cancel, list)."};
  app.require_subcommand(1);
  const int hardwareThreads = int(std::max(1u, std::thread::hardware_concurrency()));

  // render
  CLI::App* render = app.add_subcommand(
      "render",
      "render SCENE here: coordinator core and local workers in one process; writes OUT.exr, "
      "a PNG preview beside it (OUT.png) and prints a report");
  std::string renderScene, renderOutput, reportDir;
  RenderOptions renderOptions;
  int threads = hardwareThreads, workers = 1;
  render
      ->add_option("SCENE", renderScene,
                   "scene file: Mitsuba 0.6 XML, or pbrt-v3/v4 (.pbrt); its folder holds its "
                   "meshes and textures")
      ->required();
  render->add_option("-o,--output", renderOutput, "output OpenEXR file")->required();
  addRenderOptions(render, &renderOptions);
  render->add_option("--threads", threads, "chain threads in all (default: all hardware threads)")
      ->default_str(std::to_string(hardwareThreads));
  render
      ->add_option("--workers", workers,
                   "local workers sharing the threads (the image does not depend on it)")
      ->default_str("1");
  render->add_option("--report", reportDir,
                     "directory for error_vs_time.csv (elapsed_seconds,samples,rmse,relmse,"
                     "estimated_relmse; rmse and relmse need --reference) and report.json");

  farm::ClientSecurity clientSecurity;  // for every command that talks to a coordinator

  // submit
  CLI::App* submit = app.add_subcommand(
      "submit",
      "upload SCENE's directory tree (files over 256 MiB left out) and start a job; the last "
      "line of stdout is the job id");
  std::string address, submitScene;
  RenderOptions submitOptions;
  submit->add_option("--coordinator", address, "HOST:PORT of the farm-coordinator")->required();
  farm::addClientSecurityOptions(submit, &clientSecurity, "FARM", farm::Role::kSubmit);
  submit
      ->add_option("SCENE", submitScene,
                   "scene file: Mitsuba 0.6 XML, or pbrt-v3/v4 (.pbrt); its folder holds its "
                   "meshes and textures")
      ->required();
  addRenderOptions(submit, &submitOptions);

  // status
  CLI::App* status = app.add_subcommand(
      "status", "show a job's phase, fraction done, samples/s, elapsed time, ETA, Z and error");
  std::string job;
  bool json = false;
  status->add_option("--coordinator", address, "HOST:PORT of the farm-coordinator")->required();
  farm::addClientSecurityOptions(status, &clientSecurity, "FARM", farm::Role::kSubmit);
  status->add_option("JOB", job, "job id")->required();
  status->add_flag("--json", json, "print JSON instead of text");

  // fetch
  CLI::App* fetch = app.add_subcommand(
      "fetch", "wait until a job is done, then download its image to OUT.exr (and OUT.png)");
  std::string fetchOutput;
  double timeout = 0;
  fetch->add_option("--coordinator", address, "HOST:PORT of the farm-coordinator")->required();
  farm::addClientSecurityOptions(fetch, &clientSecurity, "FARM", farm::Role::kSubmit);
  fetch->add_option("JOB", job, "job id")->required();
  fetch->add_option("-o,--output", fetchOutput, "output OpenEXR file")->required();
  fetch->add_option("--timeout", timeout, "give up after this many seconds (default: wait)")
      ->check(CLI::NonNegativeNumber);

  // watch
  CLI::App* watch = app.add_subcommand(
      "watch",
      "follow a job live as the coordinator streams it: a progress bar with the fraction done, "
      "samples/s, elapsed time, ETA, error (estimate) and the workers running it, until the job "
      "ends; exits 0 when it is done");
  double watchInterval = 0.5;
  watch->add_option("--coordinator", address, "HOST:PORT of the farm-coordinator")->required();
  farm::addClientSecurityOptions(watch, &clientSecurity, "FARM", farm::Role::kSubmit);
  watch->add_option("JOB", job, "job id")->required();
  watch->add_option("--interval", watchInterval, "seconds between updates (0.1 to 10)")
      ->check(CLI::Range(0.1, 10.0))
      ->default_str("0.5");

  // compare
  CLI::App* compare = app.add_subcommand(
      "compare",
      "render SCENE with each of --algorithms for the same budget (--time S, or --spp/--mpp), "
      "one job after another, here or on --coordinator, and write a report directory: per "
      "algorithm its error_vs_time.csv, report.json and image, one chart of relative MSE "
      "against seconds (error_vs_time.png and .svg), summary.json and index.html");
  std::string compareScene, compareAlgorithms = "pt,bdpt,pssmlt,mmlt,mlt,erpt", compareDir,
                            compareCoordinator;
  RenderOptions compareOptions;
  int compareThreads = hardwareThreads;
  compare->add_option("SCENE", compareScene, "scene file")->required();
  compare
      ->add_option("--algorithms", compareAlgorithms,
                   std::string("comma-separated, from ") + farm::algorithmList())
      ->default_str(compareAlgorithms);
  compare->add_option("--report", compareDir, "the report directory")->required();
  compare->add_option("--coordinator", compareCoordinator,
                      "HOST:PORT of a farm-coordinator to render on (default: here)");
  farm::addClientSecurityOptions(compare, &clientSecurity, "FARM", farm::Role::kSubmit);
  compare->add_option("--threads", compareThreads, "chain threads, rendering here")
      ->default_str(std::to_string(hardwareThreads));
  addRenderOptions(compare, &compareOptions);
  compare->remove_option(compare->get_option("--algorithm"));

  // report
  CLI::App* report = app.add_subcommand(
      "report",
      "write a coordinator job's report directory: its error_vs_time.csv, report.json, image "
      "(once done), chart and index.html");
  std::string reportJobDir;
  report->add_option("--coordinator", address, "HOST:PORT of the farm-coordinator")->required();
  farm::addClientSecurityOptions(report, &clientSecurity, "FARM", farm::Role::kSubmit);
  report->add_option("JOB", job, "job id")->required();
  report->add_option("DIR", reportJobDir, "the report directory")->required();

  // plan
  CLI::App* planCommand = app.add_subcommand(
      "plan",
      "print what SCENE has (surfaces by kind, lights with sizes and powers, lens, textures, "
      "environment, media) and the render it implies: the algorithm (auto: the candidates, or "
      "with --pilot the pilot's pick and figures), mlt's mutation weights, and each part in or "
      "left out, and why");
  std::string planScene, planAlgorithm = "auto", planMix, planNormals = "scene";
  double planTime = 0;
  int planWidth = 0, planHeight = 0;
  bool planPilot = false;
  planCommand->add_option("SCENE", planScene, "scene file")->required();
  planCommand
      ->add_option("--algorithm", planAlgorithm,
                   std::string("the algorithm to plan for: ") + farm::algorithmList() + ", auto")
      ->default_str("auto");
  planCommand->add_option("--mutation-mix", planMix, "mlt's requested mutation weights")
      ->default_str(farm::formatMutationMix(farm::MutationMix()));
  planCommand->add_flag("--pilot", planPilot,
                        "run auto's pilot here, a few seconds per candidate, and show its pick");
  planCommand
      ->add_option("--time", planTime,
                   "the job's budget in seconds: the pilot takes 10% of it (0: 1 s a candidate)")
      ->default_str("0");
  planCommand->add_option("--width", planWidth, "film width for the pilot (default: the scene's)");
  planCommand->add_option("--height", planHeight, "film height for the pilot");
  planCommand
      ->add_option("--shading-normals", planNormals,
                   "scene, strict or lax: the convention to plan for (see `farm render --help`)")
      ->default_str("scene");
  planCommand->add_flag("--json", json, "print JSON instead of text");

  // cancel, list
  CLI::App* cancel = app.add_subcommand("cancel", "cancel a job");
  cancel->add_option("--coordinator", address, "HOST:PORT of the farm-coordinator")->required();
  farm::addClientSecurityOptions(cancel, &clientSecurity, "FARM", farm::Role::kSubmit);
  cancel->add_option("JOB", job, "job id")->required();
  CLI::App* list = app.add_subcommand("list", "list the coordinator's jobs");
  list->add_option("--coordinator", address, "HOST:PORT of the farm-coordinator")->required();
  farm::addClientSecurityOptions(list, &clientSecurity, "FARM", farm::Role::kSubmit);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return fail(std::string(e.what()) + " (see farm --help)", kUsageError);
  }

  if (*render) {
    if (threads < 1 || threads > 4096)
      return fail("--threads must be between 1 and 4096", kUsageError);
    if (workers < 1 || workers > 4096)
      return fail("--workers must be between 1 and 4096", kUsageError);
    return runRender(renderScene, renderOutput, renderOptions, threads, workers, reportDir);
  }
  if (*compare) {
    if (compareThreads < 1 || compareThreads > 4096)
      return fail("--threads must be between 1 and 4096", kUsageError);
    return runCompareCommand(compareScene, compareAlgorithms, compareOptions, compareCoordinator,
                             clientSecurity, compareThreads, compareDir);
  }
  if (*report) return runReportCommand(address, clientSecurity, job, reportJobDir);
  if (*planCommand)
    return runPlan(planScene, planAlgorithm, planMix, planNormals, planTime, planWidth, planHeight,
                   planPilot, json);
  if (*submit) return runSubmit(address, clientSecurity, submitScene, submitOptions);
  if (*status) return runStatus(address, clientSecurity, job, json);
  if (*fetch) return runFetch(address, clientSecurity, job, fetchOutput, timeout);
  if (*watch) return runWatch(address, clientSecurity, job, watchInterval);
  if (*cancel) return runCancel(address, clientSecurity, job);
  if (*list) return runList(address, clientSecurity);
  return fail("no command given (try --help)", kUsageError);
}
