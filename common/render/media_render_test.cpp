// Participating media through the whole render: the smoky room of tests/data (fog, tinted water
// in glass, a puff of smoke from a grid file) loads, and path tracing, BDPT and the
// primary-sample-space chains over them agree on it within their variance; the algorithms that
// do not track media yet refuse it with a message that names the ones that do.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "common/render/image_agreement.h"
#include "common/render/local_render.h"
#include "common/render/render_job.h"
#include "common/scene/loaders/scene_files.h"
#include "common/scene/scene.h"

namespace farm {
namespace {

const std::string kSmokyBox = std::string(FARM_TEST_DATA_DIR) + "/smoky-box/scene.xml";

Image renderSmokyBox(Algorithm algorithm, int64_t budget, uint64_t seed, double* zRel = nullptr) {
  RenderSettings s;
  s.algorithm = algorithm;
  s.samplesPerPixel = budget;
  s.mutationsPerPixel = budget;
  s.seed = seed;
  s.width = 24;
  s.height = 24;
  RenderJob job(loadScene(kSmokyBox, s), s, "smoky-box");
  LocalRenderResult r = renderLocally(job);
  EXPECT_EQ(r.rejected.total(), 0);
  if (zRel) *zRel = r.bootstrap.normalizationStdError / r.bootstrap.normalization;
  return r.image;
}

// Each algorithm that tracks media against path tracing, both twice with different seeds.
void expectAgreesWithPathTracing(Algorithm algorithm, int64_t budget) {
  Image pt[2] = {renderSmokyBox(Algorithm::PathTracing, 256, 1),
                 renderSmokyBox(Algorithm::PathTracing, 256, 2)};
  double z[2] = {0, 0};
  Image other[2] = {renderSmokyBox(algorithm, budget, 3, &z[0]),
                    renderSmokyBox(algorithm, budget, 4, &z[1])};
  const double zRel = isMarkovChain(algorithm) ? 0.5 * std::hypot(z[0], z[1]) : 0.0;
  const Agreement g = compare(pt, other, zRel);
  EXPECT_GT(g.meanA, 0.01);
  EXPECT_NEAR(g.meanA, g.meanB, 4 * g.se) << algorithmName(algorithm);
  EXPECT_LT(g.ratio, 1.5) << algorithmName(algorithm);
  std::printf(
      "smoky box: means pt %.4f %s %.4f (se %.4f), squared differences over variance "
      "%.3f\n",
      g.meanA, algorithmName(algorithm), g.meanB, g.se, g.ratio);
}

TEST(MediaRender, BidirectionalAgreesWithPathTracing) {
  expectAgreesWithPathTracing(Algorithm::Bidirectional, 64);
}
TEST(MediaRender, PssmltOverPathTracingAgreesWithPathTracing) {
  expectAgreesWithPathTracing(Algorithm::PSSMLTOverPT, 256);
}
TEST(MediaRender, PssmltAgreesWithPathTracing) {
  expectAgreesWithPathTracing(Algorithm::PSSMLT, 64);
}
TEST(MediaRender, MultiplexedAgreesWithPathTracing) {
  expectAgreesWithPathTracing(Algorithm::MMLT, 128);
}

TEST(MediaRender, AlgorithmsThatDoNotTrackMediaRefuseThem) {
  for (Algorithm algorithm : allAlgorithms()) {
    RenderSettings settings;
    settings.algorithm = algorithm;
    if (algorithm != Algorithm::MLT && algorithm != Algorithm::ERPT) {
      EXPECT_TRUE(loadScene(kSmokyBox, settings)->hasMedia());
      continue;
    }
    try {
      loadScene(kSmokyBox, settings);
      ADD_FAILURE() << algorithmName(algorithm) << " accepted a scene with media";
    } catch (const SceneLoadError& e) {
      EXPECT_NE(std::string(e.what()).find(
                    std::string("participating media are not supported by ") +
                    algorithmName(algorithm) + " yet: use pt, bdpt, pssmlt, pssmlt-pt or mmlt"),
                std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace farm
