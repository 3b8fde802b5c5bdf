// The error a job reports without a reference (batch means over its chain groups,
// common/film/batch_means.h) against the error measured with one, on the shared scenes whose
// references every algorithm converges to (cornell-box, veach-bidir, veach-mis, veach-ajar):
// within a factor of two, every algorithm; and on water-caustic, for mlt, the one algorithm that
// converges there (with manifold walks), rendered as its reference was (lax normals, 8 edges).
// Every local sampler misses a third of its light: its error against the reference is that
// deficit, which no group sees (README, "Error against run time").
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/embedded_render.h"

namespace farm {
namespace {

struct Case {
  const char* scene;  // under ../shared/scenes
  Algorithm algorithm;
  int64_t budget;  // samples or seeds per pixel (pt, bdpt, erpt), mutations otherwise
  int seeds = 1;   // renders at seeds 11, 12, ..; the median of their ratios is held
};

// The reference, its size and how it was rendered: ../shared/references' where there is one;
// veach-ajar's is this renderer's BDPT at 3590 samples a pixel (tests/data/README.md), whose own
// noise is about 1/3590 of a sample's, far below these renders' of 2-16. The water-caustic
// reference keeps paths whose sides its normals dispute and has at most 8 edges
// (docs/conventions.md): rendered otherwise, the error measured against it would
// carry that difference of means, which no group sees.
struct Target {
  std::string scene, reference;
  int width, height;
  ShadingNormals shadingNormals = ShadingNormals::Scene;
  int maxDepth = 0;  // 0: the scene file's
};

Target targetOf(const std::string& name) {
  const std::string shared = FARM_SHARED_DIR;
  if (name == "veach-ajar")
    return {shared + "/scenes/veach-ajar/scene.pbrt",
            std::string(FARM_TEST_DATA_DIR) + "/veach-ajar-bdpt-256.exr", 256, 144};
  if (name == "veach-mis")
    return {shared + "/scenes/veach-mis/scene.xml", shared + "/references/veach-mis-320.exr", 320,
            180};
  if (name == "water-caustic")
    return {shared + "/scenes/water-caustic/scene.xml",
            shared + "/references/water-caustic-256.exr",
            256,
            256,
            ShadingNormals::Lax,
            8};
  return {shared + "/scenes/" + name + "/scene.xml", shared + "/references/" + name + "-256.exr",
          256, 256};
}

class ErrorEstimate : public ::testing::TestWithParam<Case> {};

TEST_P(ErrorEstimate, IsWithinAFactorOfTwoOfTheReferencesError) {
  const Case& c = GetParam();
  std::vector<double> ratios;
  for (int k = 0; k < c.seeds; ++k) {
    EmbeddedRenderOptions o;
    o.settings.algorithm = c.algorithm;
    const Target t = targetOf(c.scene);
    o.settings.width = t.width;
    o.settings.height = t.height;
    o.settings.samplesPerPixel = c.budget;
    o.settings.mutationsPerPixel = c.budget;
    o.settings.seed = uint64_t(11 + k);
    o.settings.shadingNormals = t.shadingNormals;
    o.settings.maxDepth = t.maxDepth;
    o.scenePath = t.scene;
    o.referencePath = t.reference;
    o.threads = 2;
    EmbeddedRenderResult result;
    const Status s = renderEmbedded(o, &result);
    ASSERT_TRUE(s.isOk()) << s.message();
    ASSERT_FALSE(result.progress.errorSeries.empty());
    const ErrorSample& last = result.progress.errorSeries.back();
    EXPECT_EQ(last.samples, result.progress.workDone) << "the last sample is the final image's";
    ASSERT_GT(last.relMse, 0);
    ASSERT_GE(last.estimatedRelMse, 0) << "no estimate";
    ratios.push_back(last.estimatedRelMse / last.relMse);
    std::printf("seed %d: estimated %g, measured %g, ratio %g\n", 11 + k, last.estimatedRelMse,
                last.relMse, ratios.back());
    // The estimate is there early, not only once the last group starts: on two threads the
    // scheduler runs a chain of every group before a second of any (chain_scheduler.h), so an
    // estimate can be made after about one chain of each, 4 of 64; leasing in chain order
    // (groups are contiguous blocks of chains), not before chain 49 of 64 ends. The job measures
    // its error only while that costs it under 10% of its time (3% without a reference), which
    // on a busy machine skips flushes: the bound is half the work.
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
  std::sort(ratios.begin(), ratios.end());
  const double median = ratios[ratios.size() / 2];
  EXPECT_GT(median, 0.5);
  EXPECT_LT(median, 2.0);
}

// Budgets of one to seven seconds on two threads; erpt at 2 seeds per pixel has two groups.
// Measured at seed 11 (estimate / measured): 0.91-0.995 on cornell-box, 0.75-1.25 on
// veach-bidir, 0.89-1.32 on veach-mis, 0.72-1.27 on veach-ajar. On water-caustic, whose error
// at 16 mutations a pixel comes in rare bright splats, one render's ratio scatters by a factor of
// two from seed to seed (0.48, 0.67, 0.91, 0.86, 0.88 at seeds 11-15 at 04278a8; 0.64, 1.04,
// 0.73, 0.89, 0.92 before it): the median of five (about 2 s each) is held.
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
        Case{"veach-bidir", Algorithm::MLT, 16}, Case{"veach-bidir", Algorithm::ERPT, 2},
        Case{"veach-mis", Algorithm::PathTracing, 16},
        Case{"veach-mis", Algorithm::Bidirectional, 4}, Case{"veach-mis", Algorithm::PSSMLT, 8},
        Case{"veach-mis", Algorithm::PSSMLTOverPT, 16}, Case{"veach-mis", Algorithm::MMLT, 16},
        Case{"veach-mis", Algorithm::MLT, 16}, Case{"veach-mis", Algorithm::ERPT, 2},
        Case{"veach-ajar", Algorithm::PathTracing, 16},
        Case{"veach-ajar", Algorithm::Bidirectional, 4}, Case{"veach-ajar", Algorithm::PSSMLT, 8},
        Case{"veach-ajar", Algorithm::PSSMLTOverPT, 16}, Case{"veach-ajar", Algorithm::MMLT, 16},
        Case{"veach-ajar", Algorithm::MLT, 16}, Case{"veach-ajar", Algorithm::ERPT, 2},
        Case{"water-caustic", Algorithm::MLT, 16, 5}),
    [](const auto& info) {
      std::string name = std::string(info.param.scene) + "_" + algorithmName(info.param.algorithm);
      for (char& ch : name)
        if (ch == '-') ch = '_';
      return name;
    });

}  // namespace
}  // namespace farm
