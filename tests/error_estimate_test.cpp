// The error a job reports without a reference (batch means over its chain groups,
// common/film/batch_means.h) against the error measured with one, on the shared scenes whose
// references every algorithm converges to: within a factor of two, every algorithm. (On
// water-caustic every local sampler misses a third of the light: its error against the
// reference is that deficit, which no group sees; README, "Error without a reference".)
#include <gtest/gtest.h>

#include <string>

#include "cli/embedded_render.h"

namespace farm {
namespace {

struct Case {
  const char* scene;
  Algorithm algorithm;
  int64_t budget;  // samples or seeds per pixel (pt, bdpt, erpt), mutations otherwise
};

class ErrorEstimate : public ::testing::TestWithParam<Case> {};

TEST_P(ErrorEstimate, IsWithinAFactorOfTwoOfTheReferencesError) {
  const Case& c = GetParam();
  EmbeddedRenderOptions o;
  o.settings.algorithm = c.algorithm;
  o.settings.width = 256;
  o.settings.height = 256;
  o.settings.samplesPerPixel = c.budget;
  o.settings.mutationsPerPixel = c.budget;
  o.settings.seed = 11;
  o.scenePath = std::string(FARM_SHARED_DIR) + "/scenes/" + c.scene + "/scene.xml";
  o.referencePath = std::string(FARM_SHARED_DIR) + "/references/" + c.scene + "-256.exr";
  o.threads = 2;
  EmbeddedRenderResult result;
  const Status s = renderEmbedded(o, &result);
  ASSERT_TRUE(s.isOk()) << s.message();
  ASSERT_FALSE(result.progress.errorSeries.empty());
  const ErrorSample& last = result.progress.errorSeries.back();
  EXPECT_EQ(last.samples, result.progress.workDone) << "the last sample is the final image's";
  ASSERT_GT(last.relMse, 0);
  ASSERT_GE(last.estimatedRelMse, 0) << "no estimate";
  const double ratio = last.estimatedRelMse / last.relMse;
  EXPECT_GT(ratio, 0.5) << "estimated " << last.estimatedRelMse << ", measured " << last.relMse;
  EXPECT_LT(ratio, 2.0) << "estimated " << last.estimatedRelMse << ", measured " << last.relMse;
  // The estimate is there early, not only once the last group starts: on two threads the
  // scheduler runs a chain of every group before a second of any (chain_scheduler.h), so an
  // estimate can be made after about one chain of each, 4 of 64; leasing in chain order (groups
  // are contiguous blocks of chains), not before chain 49 of 64 ends. The job measures its
  // error only while that costs it under 10% of its time (3% without a reference), which on a
  // busy machine skips flushes: the bound is half the work.
  const ErrorSample* first = nullptr;
  for (const ErrorSample& e : result.progress.errorSeries) {
    if (e.estimatedRelMse >= 0) {
      first = &e;
      break;
    }
  }
  ASSERT_NE(first, nullptr);
  EXPECT_LE(first->samples, result.progress.workDone / 2)
      << "the first estimate came after " << first->samples << " of " << result.progress.workDone;
}

// Budgets of one to five seconds on two threads; erpt at 2 seeds per pixel has two groups.
INSTANTIATE_TEST_SUITE_P(
    SharedScenes, ErrorEstimate,
    ::testing::Values(
        Case{"cornell-box", Algorithm::PathTracing, 16},
        Case{"cornell-box", Algorithm::Bidirectional, 4}, Case{"cornell-box", Algorithm::PSSMLT, 8},
        Case{"cornell-box", Algorithm::PSSMLTOverPT, 16}, Case{"cornell-box", Algorithm::MMLT, 16},
        Case{"cornell-box", Algorithm::MLT, 16}, Case{"cornell-box", Algorithm::ERPT, 2},
        Case{"veach-bidir", Algorithm::PathTracing, 16},
        Case{"veach-bidir", Algorithm::Bidirectional, 4}, Case{"veach-bidir", Algorithm::PSSMLT, 8},
        Case{"veach-bidir", Algorithm::PSSMLTOverPT, 16}, Case{"veach-bidir", Algorithm::MMLT, 16},
        Case{"veach-bidir", Algorithm::MLT, 16}, Case{"veach-bidir", Algorithm::ERPT, 2}),
    [](const auto& info) {
      std::string name = std::string(info.param.scene) + "_" + algorithmName(info.param.algorithm);
      for (char& ch : name)
        if (ch == '-') ch = '_';
      return name;
    });

}  // namespace
}  // namespace farm
