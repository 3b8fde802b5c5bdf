// `farm render`'s pipeline in-process: the worker count does not change the image, and a time
// budget stops the chains and still resolves an image.
#include "cli/embedded_render.h"

#include <gtest/gtest.h>

#include <cmath>

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

TEST(EmbeddedRender, WorkerCountDoesNotChangeTheImage) {
  for (Algorithm a : {Algorithm::Bidirectional, Algorithm::PSSMLT}) {
    EmbeddedRenderResult one, three;
    Status s = renderEmbedded(options(a, 1, 1), &one);
    ASSERT_TRUE(s.isOk()) << s.message();
    s = renderEmbedded(options(a, 3, 3), &three);
    ASSERT_TRUE(s.isOk()) << s.message();
    ASSERT_EQ(one.image.rgb.size(), three.image.rgb.size());
    for (size_t i = 0; i < one.image.rgb.size(); ++i) {
      ASSERT_NEAR(one.image.rgb[i], three.image.rgb[i], 1e-5 * std::max(1.0f, one.image.rgb[i]))
          << algorithmName(a) << " value " << i;
    }
    EXPECT_EQ(one.progress.workDone, one.progress.plannedWork);
    EXPECT_EQ(one.metadata.count("farm:algorithm"), 1u);
  }
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

TEST(EmbeddedRender, MissingLightIsAClearError) {
  EmbeddedRenderOptions o = options(Algorithm::PSSMLT, 1, 1);
  o.scenePath = "/nonexistent/scene.xml";
  EmbeddedRenderResult result;
  Status s = renderEmbedded(o, &result);
  EXPECT_FALSE(s.isOk());
  EXPECT_NE(s.message().find("/nonexistent/scene.xml"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace farm
