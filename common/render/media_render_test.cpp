// Participating media through the whole render: the smoky room of tests/data (fog, tinted water
// in glass, a puff of smoke from a grid file) loads, and path tracing, BDPT, the
// primary-sample-space chains over them and path-space MLT agree on it within their variance,
// as MLT does in the smoke room, and ERPT with and without the smoke.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/math/statistics.h"
#include "common/render/image_agreement.h"
#include "common/render/local_render.h"
#include "common/render/render_job.h"
#include "common/scene/loaders/scene_files.h"
#include "common/scene/scene.h"
#include "common/transport/path.h"
#include "common/transport/path_tracer.h"

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
  // Z scales a chain's whole image alike, so its error enters the squared differences of
  // compare() as one term with one degree of freedom; the job-sized bootstrap keeps it within a
  // third of an average pixel's error, which at 24x24 leaves that ratio at the mercy of two
  // draws. The comparison is of the chains' transport through media, so Z is measured well:
  // 2^18 candidates, and for path-space ones, which cost most here (manifold next-event
  // estimation through the water ball), 2^16, whose larger error the means' comparison counts.
  if (needsBootstrap(algorithm)) {
    s.bootstrapSamples = algorithm == Algorithm::MLT ? 1 << 16 : 1 << 18;
  }
  s.algorithm = algorithm;
  s.samplesPerPixel = budget;
  s.mutationsPerPixel = budget;
  s.seed = seed;
  s.width = 24;
  s.height = 24;
  RenderJob job(loadScene(file, s), s, "smoky-box");
  LocalRenderResult r = renderLocally(job);
  EXPECT_EQ(r.rejected.total(), 0);
  if (zRel) *zRel = std::sqrt(r.bootstrap.normalizationRelativeVariance(r.largeSteps));
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

// The smoky box without its smoke (fog, and tinted water in the glass ball: homogeneous media
// only), written to a temporary folder; returns the scene file.
std::string writeHomogeneousSmokyBox(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::ifstream in(kSmokyBox);
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const std::string mark : {"<medium type=\"heterogeneous\"", "id=\"smoke\"/>"}) {
    const size_t at = xml.find(mark);
    if (at == std::string::npos) throw std::runtime_error("no " + mark + " in the smoky box");
    const bool medium = mark.rfind("<medium", 0) == 0;
    const size_t begin = medium ? at : xml.rfind("<shape", at);
    const std::string close = medium ? "</medium>" : "</shape>";
    xml.erase(begin, xml.find(close, at) + close.size() - begin);
  }
  const std::string file = (dir / "scene.xml").string();
  std::ofstream(file) << xml;
  return file;
}

// ERPT's seeds are path tracing's paths, vertices in media and all: each path's value is f / p
// times a scalar (its MIS weight; distances are drawn with the channels' mixture density), so
// its colour is f's as the path's own vertices give it.
TEST(MediaRender, PathTracingsRecordedPathsCarryTheirValuesColour) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("farm-recorded-paths-" + std::to_string(getpid()));
  RenderSettings settings;
  settings.width = settings.height = 24;
  auto scene = loadScene(writeHomogeneousSmokyBox(dir), settings);
  const int maxDepth = scene->maxDepth() == 0 ? -1 : scene->maxDepth();
  PathTracer tracer(*scene, maxDepth);
  Rng rng(3, 7);
  IndependentSampler sampler(&rng);
  int paths = 0, inMedia = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec2f film(rng.nextFloat() * 24, rng.nextFloat() * 24);
    tracer.visitPaths(film, sampler, [&](const PathTracer::TracedPath& seed) {
      if (!(luminance(seed.value) > 0)) return;
      Path x;
      seed.assignTo(&x);
      const PathContribution f = x.contribution(*scene, maxDepth);
      ASSERT_TRUE(f.carriesLight()) << "path " << paths;
      const Spectrum colour = seed.value / luminance(seed.value);
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(colour[c], f.color[c], 2e-3 * (1 + f.color[c]));
      ++paths;
      for (const PathVertex& v : x.vertices) inMedia += inMedium(v);
    });
  }
  EXPECT_GT(paths, 5000);
  EXPECT_GT(inMedia, paths / 10) << "too few paths scatter in the media to tell";
  std::filesystem::remove_all(dir);
}

// ERPT against path tracing in the scene of `file`. ERPT spreads each seed's energy over many
// pixels, so the pixels' errors are not independent: the standard errors come from the spread
// of whole renders' means (six of each), not from pairs of pixels.
void expectErptAgreesWithPathTracing(const std::string& file, const char* what) {
  // Per render, the mean of each of 3 x 3 blocks of the 24 x 24 film and of the whole.
  auto blockMeans = [](const Image& img) {
    std::vector<double> m(10, 0.0);
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        for (int c = 0; c < 3; ++c) {
          const double v = img.rgb[size_t(y * img.width + x) * 3 + size_t(c)];
          m[size_t(y * 3 / img.height * 3 + x * 3 / img.width)] +=
              v * 9 / (3.0 * img.rgb.size() / 3);
          m[9] += v / double(img.rgb.size());
        }
    return m;
  };
  constexpr int kRenders = 6;
  std::vector<std::vector<double>> erpt, pt;
  for (int r = 0; r < kRenders; ++r) {
    erpt.push_back(
        blockMeans(renderSmokyBox(Algorithm::ERPT, 32, uint64_t(10 + r), nullptr, 1, 0, file)));
    pt.push_back(blockMeans(
        renderSmokyBox(Algorithm::PathTracing, 64, uint64_t(20 + r), nullptr, 1, 0, file)));
  }
  for (int b = 0; b < 10; ++b) {
    std::vector<double> a, p;
    for (int r = 0; r < kRenders; ++r)
      a.push_back(erpt[size_t(r)][size_t(b)]), p.push_back(pt[size_t(r)][size_t(b)]);
    const MeanEstimate ea = meanOfIndependent(a), ep = meanOfIndependent(p);
    const double se = std::hypot(ea.standardError, ep.standardError);
    EXPECT_NEAR(ea.mean, ep.mean, 4.5 * se)
        << what << ": " << (b == 9 ? std::string("the whole image") : "block " + std::to_string(b));
    if (b == 9) std::printf("%s: means pt %.4f erpt %.4f (se %.4f)\n", what, ep.mean, ea.mean, se);
  }
}

// ERPT in the smoky box without its smoke (fog, and tinted water in the glass ball: homogeneous
// media only), its seeds' paths with path tracing's vertices in media.
TEST(MediaRender, ErptInHomogeneousMediaAgreesWithPathTracing) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("farm-homogeneous-media-" + std::to_string(getpid()));
  const std::string file = writeHomogeneousSmokyBox(dir);
  ASSERT_TRUE(loadScene(file, RenderSettings())->hasMedia());
  expectErptAgreesWithPathTracing(file, "homogeneous media");
  std::filesystem::remove_all(dir);
}

// ERPT in the smoky box with its puff of smoke from a grid file: seeds of known densities and
// the pseudo-marginal chains' own estimates (erpt_grid_seeds.h).
TEST(MediaRender, ErptThroughADensityGridAgreesWithPathTracing) {
  expectErptAgreesWithPathTracing(kSmokyBox, "density grid");
}

// Every algorithm takes the smoky box, density grid and all.
TEST(MediaRender, EveryAlgorithmTracksMediaThroughGrids) {
  for (Algorithm algorithm : allAlgorithms()) {
    RenderSettings settings;
    settings.algorithm = algorithm;
    EXPECT_TRUE(loadScene(kSmokyBox, settings)->hasMedia()) << algorithmName(algorithm);
  }
}

}  // namespace
}  // namespace farm
