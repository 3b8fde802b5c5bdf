// `farm render`'s pipeline in-process: the worker count does not change the image, and a time
// budget stops the chains and still resolves an image.
#include "cli/embedded_render.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli/render_report.h"
#include "common/render/algorithm_pilot.h"
#include "common/render/local_render.h"
#include "common/render/render_job.h"
#include "common/scene/stiff_scenes.h"

namespace farm {
namespace {

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

EmbeddedRenderOptions options(Algorithm algorithm, int threads, int workers) {
  EmbeddedRenderOptions o;
  o.settings.algorithm = algorithm;
  o.settings.width = 24;
  o.settings.height = 24;
  o.settings.samplesPerPixel = 8;
  o.settings.mutationsPerPixel = 8;
  o.settings.bootstrapSamples = 20000;
  o.settings.seed = 5;
  o.scenePath = kScene;
  o.threads = threads;
  o.workers = workers;
  return o;
}

// The same image, value by value, up to float rounding in another order of summation (relative
// to `expected`'s values, absolute below 1).
void expectSameImage(const Image& actual, const Image& expected, Algorithm a) {
  ASSERT_EQ(actual.rgb.size(), expected.rgb.size());
  for (size_t i = 0; i < expected.rgb.size(); ++i) {
    ASSERT_NEAR(actual.rgb[i], expected.rgb[i], 1e-5 * std::max(1.0f, expected.rgb[i]))
        << algorithmName(a) << " value " << i;
  }
}

TEST(EmbeddedRender, WorkerCountDoesNotChangeTheImage) {
  for (Algorithm a : {Algorithm::Bidirectional, Algorithm::PSSMLT}) {
    EmbeddedRenderResult one, three;
    Status s = renderEmbedded(options(a, 1, 1), &one);
    ASSERT_TRUE(s.isOk()) << s.message();
    s = renderEmbedded(options(a, 3, 3), &three);
    ASSERT_TRUE(s.isOk()) << s.message();
    ASSERT_NO_FATAL_FAILURE(expectSameImage(three.image, one.image, a));
    EXPECT_EQ(one.progress.workDone, one.progress.plannedWork);
    EXPECT_EQ(one.metadata.count("farm:algorithm"), 1u);
  }
}

// The farm scales the image by Z pooled from the bootstrap and the large steps its flushes
// carried (common/mcmc/normalization.h), as renderLocally does: the same job and seed give the
// same image both ways, and a coordinator that left the large steps out (the bootstrap's Z
// alone, about 0.5% off here) would not.
TEST(EmbeddedRender, ZPoolsTheLargeStepsAsARenderHereDoes) {
  for (Algorithm a : {Algorithm::PSSMLT, Algorithm::MMLT}) {
    EmbeddedRenderOptions o = options(a, 2, 1);
    o.settings.bootstrapSamples = 4096;  // a rough Z, for the large steps to refine
    EmbeddedRenderResult farm;
    Status s = renderEmbedded(o, &farm);
    ASSERT_TRUE(s.isOk()) << s.message();
    RenderSettings settings = o.settings;
    const LocalRenderResult here =
        renderLocally(RenderJob(loadScene(kScene, settings), settings, "here"));
    ASSERT_GT(here.largeSteps.count, 0);
    EXPECT_EQ(farm.progress.largeSteps, here.largeSteps.count) << algorithmName(a);
    const Normalization z = here.bootstrap.normalizationWith(here.largeSteps);
    EXPECT_NEAR(farm.progress.normalization, z.value, 1e-9 * z.value) << algorithmName(a);
    EXPECT_LT(z.stdError, here.bootstrap.normalizationStdError) << algorithmName(a);
    EXPECT_GT(std::abs(z.value / here.bootstrap.normalization - 1), 1e-6)
        << "the large steps moved Z (else this test could not tell)";
    ASSERT_NO_FATAL_FAILURE(expectSameImage(farm.image, here.image, a));
    EXPECT_EQ(farm.metadata.at("farm:normalizationLargeSteps"),
              std::to_string(here.largeSteps.count));
    EXPECT_NE(finalReport(farm.progress, "cornell-box", "").find(" large steps;"),
              std::string::npos);
  }
}

// With Kelemen's combination (--combine-large-steps) the large steps are part of the image and
// not samples of Z: the setting reaches the workers (the image is not the chain's alone), the
// image is the one a render here makes, and Z is the bootstrap's.
TEST(EmbeddedRender, CombinedLargeStepsReachTheWorkersAndLeaveZAlone) {
  for (Algorithm a : {Algorithm::PSSMLT, Algorithm::MMLT}) {
    EmbeddedRenderOptions o = options(a, 2, 1);
    EmbeddedRenderResult alone;
    Status s = renderEmbedded(o, &alone);
    ASSERT_TRUE(s.isOk()) << s.message();
    o.settings.combineLargeSteps = true;
    EmbeddedRenderResult farm;
    s = renderEmbedded(o, &farm);
    ASSERT_TRUE(s.isOk()) << s.message();
    RenderSettings settings = o.settings;
    const LocalRenderResult here =
        renderLocally(RenderJob(loadScene(kScene, settings), settings, "here"));
    EXPECT_EQ(here.largeSteps.count, 0) << algorithmName(a);
    EXPECT_EQ(farm.progress.largeSteps, 0) << algorithmName(a);
    EXPECT_NEAR(farm.progress.normalization, here.bootstrap.normalization,
                1e-9 * here.bootstrap.normalization)
        << algorithmName(a);
    ASSERT_NO_FATAL_FAILURE(expectSameImage(farm.image, here.image, a));
    ASSERT_EQ(alone.image.rgb.size(), here.image.rgb.size());
    size_t differ = 0;
    for (size_t i = 0; i < here.image.rgb.size(); ++i) {
      if (std::abs(farm.image.rgb[i] - alone.image.rgb[i]) > 1e-4f * alone.image.rgb[i]) ++differ;
    }
    EXPECT_GT(differ, here.image.rgb.size() / 2) << algorithmName(a);
    EXPECT_EQ(farm.metadata.at("farm:combineLargeSteps"), "1");
  }
  // Only a chain in primary sample space has large steps to combine; auto may pick one.
  RenderSettings s = options(Algorithm::Bidirectional, 1, 1).settings;
  s.combineLargeSteps = true;
  EXPECT_NE(s.validate().find("--combine-large-steps weights large steps into a chain"),
            std::string::npos);
  s.autoAlgorithm = true;
  EXPECT_EQ(s.validate(), "");
}

TEST(EmbeddedRender, TimeBudgetStopsTheChains) {
  EmbeddedRenderOptions o = options(Algorithm::PathTracing, 2, 1);
  o.settings.timeBudgetSeconds = 1.0;
  EmbeddedRenderResult result;
  const auto start = std::chrono::steady_clock::now();
  Status s = renderEmbedded(o, &result);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(s.isOk()) << s.message();
  EXPECT_GT(result.progress.workDone, 0);
  EXPECT_GE(seconds, 0.9);
  EXPECT_LT(seconds, 10);
  EXPECT_EQ(result.progress.fraction, 1.0);
  double sum = 0;
  for (float v : result.image.rgb) sum += v;
  EXPECT_GT(sum, 0);
}

TEST(EmbeddedRender, ReferenceGivesAnErrorSeries) {
  EmbeddedRenderOptions o = options(Algorithm::PathTracing, 2, 1);
  o.settings.width = 256;
  o.settings.height = 256;
  o.settings.samplesPerPixel = 2;
  o.referencePath = std::string(FARM_SHARED_DIR) + "/references/cornell-box-256.exr";
  EmbeddedRenderResult result;
  Status s = renderEmbedded(o, &result);
  ASSERT_TRUE(s.isOk()) << s.message();
  ASSERT_FALSE(result.progress.errorSeries.empty());
  const ErrorSample& last = result.progress.errorSeries.back();
  EXPECT_EQ(last.samples, result.progress.workDone);
  EXPECT_GT(last.rmse, 0);
  EXPECT_GT(last.relMse, 0);
  EXPECT_LT(last.relMse, result.progress.errorSeries.front().relMse + 1e-12);
}

// A Markov chain job that leaves the bootstrap to size itself: its progress carries the count
// and the report sets Z's error beside the pixel model and, against a reference, says what share
// of the relative MSE it alone makes ((Z's relative error)^2 / relMSE).
TEST(EmbeddedRender, ReportShowsTheBootstrapsSizeAndZsShareOfTheError) {
  EmbeddedRenderOptions o = options(Algorithm::PSSMLT, 2, 1);
  const std::string reference = std::string(FARM_SHARED_DIR) + "/references/cornell-box-256.exr";
  o.settings.width = o.settings.height = 256;  // the reference's size
  o.settings.mutationsPerPixel = 2;
  o.settings.bootstrapSamples = 0;
  o.referencePath = reference;
  EmbeddedRenderResult result;
  Status s = renderEmbedded(o, &result);
  ASSERT_TRUE(s.isOk()) << s.message();
  const JobProgress& p = result.progress;
  // 256 x 256 x 2 mutations: 5% of them is 6898 candidates, more than the pilot.
  EXPECT_EQ(p.bootstrapCandidates, 6898);
  const double zRel = p.normalizationStdError / p.normalization;
  ASSERT_GT(zRel, 0);
  const nlohmann::json j = progressJson(p);
  EXPECT_EQ(j["bootstrap_candidates"].get<int64_t>(), 6898);
  const std::string report = finalReport(p, "cornell-box", reference);
  EXPECT_NE(report.find("from 6898 candidates"), std::string::npos) << report;
  EXPECT_NE(report.find("at one splat per unit of work: 70.7%"), std::string::npos) << report;
  ASSERT_FALSE(p.errorSeries.empty());
  const double share = 100 * zRel * zRel / p.errorSeries.back().relMse;
  char expected[96];
  std::snprintf(expected, sizeof(expected), "alone would make about %.2g%% of it", share);
  EXPECT_NE(report.find(expected), std::string::npos) << expected << "\n" << report;
  // Connections manifold next-event estimation gave up on: named only where there are some.
  EXPECT_EQ(p.abandonedConnections, 0);  // pssmlt has no such estimator
  EXPECT_EQ(report.find("gave up on"), std::string::npos) << report;
  JobProgress withSome = p;
  withSome.abandonedConnections = 3;
  EXPECT_NE(finalReport(withSome, "cornell-box", reference).find("gave up on 3 connection(s)"),
            std::string::npos);
  EXPECT_EQ(progressJson(withSome)["abandoned_connections"].get<int64_t>(), 3);
  // Where Z's standard error is above 1%, the report says what a bootstrap that brings it to
  // 0.5% would take: (2%/0.5%)^2 = 16 times the candidates and their time.
  EXPECT_LT(zRel, 0.01);
  EXPECT_EQ(report.find("--bootstrap-candidates"), std::string::npos) << report;
  JobProgress uncertain = p;
  uncertain.normalizationStdError = 0.02 * p.normalization;
  uncertain.bootstrapCandidates = 70000;
  uncertain.bootstrapSeconds = 3;
  const std::string hint = finalReport(uncertain, "cornell-box", reference);
  EXPECT_NE(hint.find("uncertain by Z's 2%: --bootstrap-candidates 1120000 would bring that to "
                      "about 0.5%, at about 48 s of bootstrap"),
            std::string::npos)
      << hint;
}

// --flush-every sets the work between a chain's flushes; the image does not depend on it.
TEST(EmbeddedRender, FlushIntervalChangesTheFlushesNotTheImage) {
  for (Algorithm a : {Algorithm::PathTracing, Algorithm::PSSMLT, Algorithm::MLT}) {
    EmbeddedRenderOptions o = options(a, 2, 1);
    o.settings.numChains = 2;  // 2304 each: the default flushes once, 300 eight times
    EmbeddedRenderResult standard, frequent;
    ASSERT_TRUE(renderEmbedded(o, &standard).isOk());
    o.settings.flushInterval = 300;
    ASSERT_TRUE(renderEmbedded(o, &frequent).isOk());
    EXPECT_EQ(frequent.progress.workDone, standard.progress.workDone);
    double worst = 0;
    for (size_t i = 0; i < standard.image.rgb.size(); ++i) {
      const double a0 = standard.image.rgb[i], b0 = frequent.image.rgb[i];
      if (std::abs(a0) > 1e-3) worst = std::max(worst, std::abs(a0 - b0) / std::abs(a0));
    }
    EXPECT_LT(worst, 1e-5) << algorithmName(a);

    RenderJob job(loadScene(kScene, o.settings), o.settings, "flushes");
    for (const ChainSpec& spec : job.planChains(job.bootstrap())) {
      ASSERT_EQ(spec.budget, 2304);
      EXPECT_EQ(spec.flushInterval, 300) << algorithmName(a);
    }
  }
}

TEST(EmbeddedRender, MissingLightIsAClearError) {
  EmbeddedRenderOptions o = options(Algorithm::PSSMLT, 1, 1);
  o.scenePath = "/nonexistent/scene.xml";
  EmbeddedRenderResult result;
  Status s = renderEmbedded(o, &result);
  EXPECT_FALSE(s.isOk());
  EXPECT_NE(s.message().find("/nonexistent/scene.xml"), std::string::npos) << s.message();
}

// A light too bright for float (3e38 per unit area, times the pixel count of the splat
// convention): the splats that see it are infinite. They are counted by cause where they are
// made and none reaches the image, which stays finite; the job's progress carries the counts.
TEST(EmbeddedRender, InvalidSplatsAreCountedAndKeptOut) {
  const std::string path = (std::filesystem::temp_directory_path() / "too-bright.xml").string();
  std::ofstream(path) << R"(<?xml version="1.0"?>
<scene version="0.5.0">
  <sensor type="perspective">
    <float name="fov" value="60"/>
    <transform name="toWorld"><lookat origin="0, 3, -1" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film>
  </sensor>
  <shape type="rectangle">
    <transform name="toWorld"><scale value="3"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"/>
  </shape>
  <shape type="rectangle">
    <transform name="toWorld"><scale value="0.5"/><rotate x="1" angle="-90"/>
      <translate y="0.01"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0 0 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="3e38 3e38 3e38"/></emitter>
  </shape>
</scene>
)";
  EmbeddedRenderOptions o = options(Algorithm::PathTracing, 2, 1);
  o.scenePath = path;
  EmbeddedRenderResult result;
  Status s = renderEmbedded(o, &result);
  ASSERT_TRUE(s.isOk()) << s.message();
  EXPECT_GT(result.progress.rejected.infinite, 0);
  EXPECT_EQ(result.progress.rejected.nan, 0);
  EXPECT_EQ(result.progress.rejected.negative, 0);
  for (float v : result.image.rgb) ASSERT_TRUE(std::isfinite(v) && v >= 0);
  std::printf("infinite splats kept out: %lld\n", (long long)result.progress.rejected.infinite);
}

// Degenerate triangles are left out by the loader with a warning that reaches the job's progress
// (so `farm status` and the final report) and the report's text.
TEST(EmbeddedRender, SceneWarningsReachTheReport) {
  EmbeddedRenderOptions o = options(Algorithm::PathTracing, 1, 1);
  o.scenePath = stiff::furnaceBoxFile(true, 4);
  o.settings.width = o.settings.height = 8;
  EmbeddedRenderResult result;
  Status s = renderEmbedded(o, &result);
  ASSERT_TRUE(s.isOk()) << s.message();
  ASSERT_EQ(result.progress.warnings.size(), 1u);
  EXPECT_NE(result.progress.warnings[0].find("5 degenerate triangles left out"), std::string::npos)
      << result.progress.warnings[0];
  EXPECT_NE(statusText(result.progress).find("scene warning: " + result.progress.warnings[0]),
            std::string::npos)
      << statusText(result.progress);
}

// --shading-normals overrides the scene file's convention: the water caustic (strictNormals true
// in its file) rendered lax with the same seed is another image (its camera rays through the
// wavy surface's underside, which strict normals end, go on), brighter, and says so in its
// metadata; strict is the file's image. (ClusterTest.FetchedImageMatchesEmbeddedRender/
// pt_water_caustic_lax checks that remote workers get the override.)
TEST(EmbeddedRender, ShadingNormalsOverrideTheScenes) {
  auto render = [](ShadingNormals normals) {
    EmbeddedRenderOptions o = options(Algorithm::PathTracing, 2, 2);
    o.scenePath = std::string(FARM_SHARED_DIR) + "/scenes/water-caustic/scene.xml";
    o.settings.shadingNormals = normals;
    EmbeddedRenderResult result;
    Status s = renderEmbedded(o, &result);
    EXPECT_TRUE(s.isOk()) << s.message();
    return result;
  };
  const EmbeddedRenderResult file = render(ShadingNormals::Scene),
                             strict = render(ShadingNormals::Strict),
                             lax = render(ShadingNormals::Lax);
  EXPECT_EQ(file.metadata.at("farm:shadingNormals"), "strict");
  EXPECT_EQ(strict.metadata.at("farm:shadingNormals"), "strict");
  EXPECT_EQ(lax.metadata.at("farm:shadingNormals"), "lax");
  ASSERT_EQ(lax.image.rgb.size(), file.image.rgb.size());
  EXPECT_EQ(strict.image.rgb, file.image.rgb);
  double sumStrict = 0, sumLax = 0;
  size_t differ = 0;
  for (size_t i = 0; i < lax.image.rgb.size(); ++i) {
    sumStrict += strict.image.rgb[i];
    sumLax += lax.image.rgb[i];
    differ += lax.image.rgb[i] != strict.image.rgb[i];
  }
  EXPECT_GT(differ, lax.image.rgb.size() / 10);
  EXPECT_GT(sumLax, sumStrict);
}

// --algorithm auto --pilot: the pilot takes about a tenth of the budget, the job renders with its
// pick, and the report says what the plan chose and why.
TEST(EmbeddedRender, AutoRendersWithThePilotsPickAndReportsThePlan) {
  EmbeddedRenderOptions o = options(Algorithm::PSSMLT, 2, 1);
  o.settings.autoAlgorithm = true;
  o.settings.pilot = true;
  o.settings.bootstrapSamples = 0;
  // Counts, not a budget: a pilot of a second a candidate.
  EmbeddedRenderResult result;
  Status s = renderEmbedded(o, &result);
  ASSERT_TRUE(s.isOk()) << s.message();
  const JobProgress& p = result.progress;
  EXPECT_EQ(p.phase, JobPhase::kDone);
  EXPECT_FALSE(p.settings.autoAlgorithm);
  EXPECT_GT(p.workDone, 0);
  const std::string report = finalReport(p, o.scenePath, "");
  EXPECT_NE(report.find("  plan:\n"), std::string::npos) << report;
  EXPECT_NE(
      report.find(std::string("algorithm: ") + algorithmName(p.settings.algorithm) + " (auto)"),
      std::string::npos)
      << report;
  // Each candidate's pilot, with its figures (the Cornell box has three).
  size_t pilots = 0;
  for (const std::string& line : p.renderPlan) pilots += line.find("  pilot ") == 0;
  EXPECT_EQ(pilots, 3u) << report;
  EXPECT_NE(report.find("left out: lens sampling (pinhole camera"), std::string::npos) << report;
  // The pilot took its second a candidate before the render.
  EXPECT_GT(p.elapsedSeconds - p.renderSeconds, 2.9);
  EXPECT_LT(p.elapsedSeconds, 10.0);
  EXPECT_EQ(result.metadata.at("farm:algorithm"), algorithmName(p.settings.algorithm));

  // What it cannot do, said before anything runs.
  RenderSettings bad = o.settings;
  bad.ignorePlan = true;
  EXPECT_NE(bad.validate().find("--no-plan"), std::string::npos);
}

// --until-error: the job stops once the error estimated from its chain groups is there,
// long before its budget, and says so; the report's CSV carries the estimate with no reference.
TEST(EmbeddedRender, UntilErrorStopsOnceTheEstimateIsThere) {
  EmbeddedRenderOptions o = options(Algorithm::PSSMLT, 2, 1);
  o.settings.width = o.settings.height = 64;
  o.settings.mutationsPerPixel = 1024;  // about 18 s on two threads; 0.001 comes at about 4
  o.settings.bootstrapSamples = 0;
  o.settings.untilError = 1e-3;
  EmbeddedRenderResult result;
  Status s = renderEmbedded(o, &result);
  ASSERT_TRUE(s.isOk()) << s.message();
  const JobProgress& p = result.progress;
  EXPECT_EQ(p.phase, JobPhase::kDone);
  EXPECT_LT(p.workDone, p.plannedWork / 2) << "it ran (almost) its whole budget";
  ASSERT_FALSE(p.errorSeries.empty());
  EXPECT_LT(p.errorSeries.back().estimatedRelMse, 1e-3);
  EXPECT_LT(p.errorSeries.back().relMse, 0) << "no reference, no measured error";
  // It stopped at the first estimate within the target, give or take the flushes under way.
  size_t reached = p.errorSeries.size();
  for (size_t i = 0; i < p.errorSeries.size() && reached == p.errorSeries.size(); ++i)
    if (p.errorSeries[i].estimatedRelMse <= 1e-3) reached = i;
  ASSERT_LT(reached, p.errorSeries.size());
  EXPECT_LT(p.workDone, p.errorSeries[reached].samples * 5 / 4);
  EXPECT_NE(statusText(p).find("stops at 0.001"), std::string::npos) << statusText(p);

  const std::string dir = ::testing::TempDir() + "/until-error-report";
  std::string error;
  ASSERT_TRUE(writeReportDir(dir, p, o.scenePath, "out.exr", "", &error)) << error;
  std::ifstream csv(dir + "/error_vs_time.csv");
  std::string header, row;
  std::getline(csv, header);
  EXPECT_EQ(header, "elapsed_seconds,samples,rmse,relmse,estimated_relmse");
  ASSERT_TRUE(std::getline(csv, row));
  EXPECT_NE(row.find(",,,"), std::string::npos) << "empty reference columns: " << row;

  // What it cannot do, said before anything runs.
  RenderSettings bad = o.settings;
  bad.untilError = -1;
  EXPECT_NE(bad.validate().find("--until-error must be a relative MSE >= 0"), std::string::npos);
  bad.untilError = 1e-3;
  bad.errorGroups = 1;
  EXPECT_NE(bad.validate().find("--until-error needs an error estimate"), std::string::npos);
}

// --algorithm auto where the plan renders bdpt with a time budget keeps its allocation pilot's
// samples in the image (algorithm_pilot.h, PilotSamples): uniform samples under the pilot's own
// seed, pooled with the allocated ones and counted in the work. The pooled image's channel means
// agree with those of two uniform bdpt renders of other seeds within 4 standard errors (each
// from the uniform renders' pixel variances, the pooled render's scaled by its samples and its
// lowest density), and the pilot's share is large enough that its splats without its count, or
// its count without its splats, would be many standard errors away.
TEST(EmbeddedRender, AnAllocationPilotsSamplesPoolIntoTheImageUnbiased) {
  const std::string scene = std::string(FARM_TEST_DATA_DIR) + "/smoky-box/scene.xml";
  EmbeddedRenderOptions o;
  o.settings.autoAlgorithm = true;
  o.settings.width = o.settings.height = 32;
  o.settings.timeBudgetSeconds = 5;  // a pilot of 0.5 s
  o.settings.seed = 5;
  o.scenePath = scene;
  o.threads = 2;
  o.workers = 1;
  EmbeddedRenderResult pooled;
  Status s = renderEmbedded(o, &pooled);
  ASSERT_TRUE(s.isOk()) << s.message();
  const JobProgress& p = pooled.progress;
  ASSERT_EQ(p.settings.algorithm, Algorithm::Bidirectional);
  ASSERT_TRUE(p.settings.pixelAllocation);
  const int64_t pilot = p.pilotWork, total = p.workDone;
  ASSERT_GT(pilot, 0);
  EXPECT_EQ(pooled.metadata.at("farm:pilotSamples"), std::to_string(pilot));
  EXPECT_EQ(pooled.metadata.at("farm:samples"), std::to_string(total)) << "the pilot's among them";
  EXPECT_EQ(pooled.metadata.at("farm:pilotSeed"), std::to_string(5 ^ kAllocationSeedSalt));
  const double share = double(pilot) / double(total);
  const std::vector<float>& density = p.settings.pixelAllocation->density();
  const double lowest = *std::min_element(density.begin(), density.end());

  constexpr int64_t kSpp = 128;
  Image uniform[2];
  for (int k = 0; k < 2; ++k) {
    RenderSettings u;
    u.algorithm = Algorithm::Bidirectional;
    u.width = u.height = 32;
    u.samplesPerPixel = kSpp;
    u.seed = 2000 + k;
    uniform[k] = renderLocally(RenderJob(loadScene(scene, u), u, "uniform")).image;
  }
  const size_t n = size_t(32) * 32;
  for (int ch = 0; ch < 3; ++ch) {
    double sum = 0, uniformSum = 0, var = 0;  // var: of one uniform render's sum
    for (size_t i = 0; i < n; ++i) {
      const double a = uniform[0].rgb[3 * i + ch], b = uniform[1].rgb[3 * i + ch];
      sum += pooled.image.rgb[3 * i + ch];
      uniformSum += 0.5 * (a + b);
      var += (a - b) * (a - b) / 2;
    }
    const double mean = sum / double(n), uniformMean = uniformSum / double(n);
    const double seUniform = std::sqrt(var / 2) / double(n);
    const double sePooled =
        std::sqrt(var * double(kSpp * int64_t(n)) / double(total) / lowest) / double(n);
    const double se = std::hypot(seUniform, sePooled);
    EXPECT_NEAR(mean, uniformMean, 4 * se)
        << "channel " << ch << ": the pilot's " << pilot << " of " << total << " samples";
    // The pilot's splats or its count alone would move the mean by about its share: the test
    // must be able to see that.
    EXPECT_LT(4 * se, 0.25 * share * uniformMean) << "channel " << ch;
    std::printf("channel %d: pooled %.5f, uniform %.5f, standard error %.2g, pilot's share %.3f\n",
                ch, mean, uniformMean, se, share);
  }
}

}  // namespace
}  // namespace farm

namespace farm {
namespace {

// A pixel allocation reaches the workers in every work unit (it changes the image, and the
// farm's image is the one a render here makes with it); a job whose film is not the
// allocation's is refused with both sizes named.
TEST(EmbeddedRender, PixelAllocationReachesTheWorkers) {
  EmbeddedRenderOptions o = options(Algorithm::Bidirectional, 2, 2);
  std::vector<float> density;
  std::vector<uint8_t> bidirectional;
  for (int c = 0; c < 36; ++c) {  // 6x6 cells of 4 pixels
    density.push_back(float(1 + c % 4));
    bidirectional.push_back(uint8_t(c % 3 == 0));
  }
  o.settings.pixelAllocation =
      std::make_shared<const PixelAllocation>(24, 24, 4, density, bidirectional);
  EmbeddedRenderResult farm, uniform;
  Status s = renderEmbedded(o, &farm);
  ASSERT_TRUE(s.isOk()) << s.message();
  RenderSettings settings = o.settings;
  const LocalRenderResult here =
      renderLocally(RenderJob(loadScene(kScene, settings), settings, "here"));
  ASSERT_NO_FATAL_FAILURE(expectSameImage(farm.image, here.image, Algorithm::Bidirectional));
  EXPECT_EQ(farm.metadata.at("farm:pixelAllocation"),
            "6x6 cells of 4 pixels, 12 bidirectional, densities 1 to 4");
  o.settings.pixelAllocation.reset();
  s = renderEmbedded(o, &uniform);
  ASSERT_TRUE(s.isOk()) << s.message();
  size_t differ = 0;
  for (size_t i = 0; i < here.image.rgb.size(); ++i)
    if (farm.image.rgb[i] != uniform.image.rgb[i]) ++differ;
  EXPECT_GT(differ, here.image.rgb.size() / 2);

  o.settings.pixelAllocation = std::make_shared<const PixelAllocation>(
      24, 12, 4, std::vector<float>(18, 1.0f), std::vector<uint8_t>(18, 0));
  o.settings.height = 0;  // the scene's aspect: 24x24, not the allocation's 24x12
  s = renderEmbedded(o, &farm);
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.message().find("pixel allocation is for a film of 24x12"), std::string::npos)
      << s.message();
}

}  // namespace
}  // namespace farm
