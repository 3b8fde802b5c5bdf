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
const std::string kSmokeRoom = std::string(FARM_TEST_DATA_DIR) + "/smoke-room/scene.xml";

Image renderSmokyBox(Algorithm algorithm, int64_t budget, uint64_t seed, double* zRel = nullptr,
                     int mediumSamples = 1, int marchSteps = 0,
                     const std::string& file = kSmokyBox) {
  RenderSettings s;
  s.mediumSamples = mediumSamples;
  s.mediumMarchSteps = marchSteps;
  // Path-space candidates cost most here (manifold next-event estimation through the water
  // ball): a quarter of the default, whose larger error in Z the comparison counts.
  if (algorithm == Algorithm::MLT) s.bootstrapSamples = 1 << 16;
  s.algorithm = algorithm;
  s.samplesPerPixel = budget;
  s.mutationsPerPixel = budget;
  s.seed = seed;
  s.width = 24;
  s.height = 24;
  RenderJob job(loadScene(file, s), s, "smoky-box");
  LocalRenderResult r = renderLocally(job);
  EXPECT_EQ(r.rejected.total(), 0);
  if (zRel) *zRel = r.bootstrap.normalizationStdError / r.bootstrap.normalization;
  return r.image;
}

// Each algorithm that tracks media against path tracing, both twice with different seeds.
void expectAgreesWithPathTracing(Algorithm algorithm, int64_t budget, int mediumSamples = 1,
                                 int marchSteps = 0, const std::string& file = kSmokyBox) {
  Image pt[2] = {renderSmokyBox(Algorithm::PathTracing, 256, 1, nullptr, 1, 0, file),
                 renderSmokyBox(Algorithm::PathTracing, 256, 2, nullptr, 1, 0, file)};
  double z[2] = {0, 0};
  Image other[2] = {renderSmokyBox(algorithm, budget, 3, &z[0], mediumSamples, marchSteps, file),
                    renderSmokyBox(algorithm, budget, 4, &z[1], mediumSamples, marchSteps, file)};
  const double zRel = isMarkovChain(algorithm) ? 0.5 * std::hypot(z[0], z[1]) : 0.0;
  const Agreement g = compare(pt, other, zRel);
  EXPECT_GT(g.meanA, 0.01);
  EXPECT_NEAR(g.meanA, g.meanB, 4 * g.se) << algorithmName(algorithm);
  EXPECT_LT(g.ratio, 1.5) << algorithmName(algorithm);
  std::printf(
      "%s: means pt %.4f %s %.4f (se %.4f), squared differences over variance "
      "%.3f\n",
      file == kSmokyBox ? "smoky box" : "smoke room", g.meanA, algorithmName(algorithm), g.meanB,
      g.se, g.ratio);
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

// Path-space MLT, its chains' vertices in the fog, the water and the smoke (at 1024 mutations
// a pixel: at 256, its chains, most of whose moves are perturbations, leave errors so uneven
// over this small film that the squared differences come out at 1.8 to 2 times the variance
// their pairs show; at 1024, 1.04, and each mutation alone with the bidirectional one 0.64 to
// 1.3); then in the smoke room, whose grid weighs in every path: pseudo-marginal (the smoke's
// transmittances by one ratio-tracking estimate, and by the mean of four), and with them
// marched finely.
TEST(MediaRender, PathSpaceMltAgreesWithPathTracing) {
  expectAgreesWithPathTracing(Algorithm::MLT, 1024);
}
TEST(MediaRender, PseudoMarginalMltAgreesWithPathTracingThroughSmoke) {
  expectAgreesWithPathTracing(Algorithm::MLT, 256, 1, 0, kSmokeRoom);
}
TEST(MediaRender, PseudoMarginalMltWithSeveralEstimatesAgreesWithPathTracingThroughSmoke) {
  expectAgreesWithPathTracing(Algorithm::MLT, 256, 4, 0, kSmokeRoom);
}
TEST(MediaRender, MltWithMarchedTransmittanceAgreesWithPathTracingThroughSmoke) {
  expectAgreesWithPathTracing(Algorithm::MLT, 256, 1, 256, kSmokeRoom);
}

TEST(MediaRender, AlgorithmsThatDoNotTrackMediaRefuseThem) {
  for (Algorithm algorithm : allAlgorithms()) {
    RenderSettings settings;
    settings.algorithm = algorithm;
    if (algorithm != Algorithm::ERPT) {
      EXPECT_TRUE(loadScene(kSmokyBox, settings)->hasMedia());
      continue;
    }
    try {
      loadScene(kSmokyBox, settings);
      ADD_FAILURE() << algorithmName(algorithm) << " accepted a scene with media";
    } catch (const SceneLoadError& e) {
      EXPECT_NE(
          std::string(e.what()).find(std::string("participating media are not supported by ") +
                                     algorithmName(algorithm) +
                                     " yet: use pt, bdpt, pssmlt, pssmlt-pt, mmlt or mlt"),
          std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace farm
