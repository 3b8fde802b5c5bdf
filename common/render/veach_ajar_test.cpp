// veach-ajar (pbrt-v3, PLY meshes, three PNG textures, rough metals, a glass pot; one light
// behind a door left ajar) renders with every algorithm the farm has: finite, non-negative, and
// with its textures visible. Visible means the landscape picture on the wall shows its sky above
// its land: the ratio of blue to red over the picture's top rows is several times that over its
// bottom rows. The light is white and the lighting over the small picture smooth, so a texture
// lookup that returned a constant (or one colour for the whole picture) would give the two rows
// the same ratio. Agreement with the stored long BDPT render is in reference_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/film/error_metrics.h"
#include "common/render/local_render.h"
#include "common/scene/scene.h"

namespace farm {
namespace {

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/veach-ajar/scene.pbrt";

// Sum of a rectangle of the image, in fractions of its size.
Spectrum regionSum(const Image& img, double x0, double x1, double y0, double y1) {
  Spectrum sum(0.0f);
  for (int y = int(y0 * img.height); y < int(y1 * img.height); ++y)
    for (int x = int(x0 * img.width); x < int(x1 * img.width); ++x) sum += img.at(x, y);
  return sum;
}

void expectRendersWithTextures(Algorithm algorithm, int64_t perPixel) {
  RenderSettings s;
  s.algorithm = algorithm;
  s.width = 128;
  s.height = 72;
  s.samplesPerPixel = s.mutationsPerPixel = perPixel;
  s.seed = 7;
  auto scene = loadScene(kScene, s);
  RenderJob job(scene, s, "veach-ajar");
  LocalRenderResult r = renderLocally(job);
  ASSERT_EQ(r.image.width, 128);
  ASSERT_EQ(r.image.height, 72);
  EXPECT_EQ(r.rejected.total(), 0);
  int nonFinite = 0, negative = 0;
  double total = 0;
  for (float v : r.image.rgb) {
    nonFinite += !std::isfinite(v);
    negative += v < 0;
    total += v;
  }
  EXPECT_EQ(nonFinite, 0) << algorithmName(algorithm);
  EXPECT_EQ(negative, 0) << algorithmName(algorithm);
  EXPECT_GT(total, 0) << algorithmName(algorithm);
  // The picture covers x 0.31..0.54, y 0.22..0.41 of the film (sky above land, within its
  // frame); its top and bottom bands:
  Spectrum top = regionSum(r.image, 0.34, 0.51, 0.23, 0.27);
  Spectrum bottom = regionSum(r.image, 0.34, 0.51, 0.36, 0.40);
  const double topRatio = top.z / top.x, bottomRatio = bottom.z / bottom.x;
  EXPECT_GT(topRatio, 3 * bottomRatio) << algorithmName(algorithm) << ": blue/red " << topRatio
                                       << " at the top, " << bottomRatio << " at the bottom";
  std::printf("veach-ajar %s: mean %.4f, picture blue/red %.3f top, %.3f bottom\n",
              algorithmName(algorithm), total / double(r.image.rgb.size()), topRatio, bottomRatio);
}

TEST(VeachAjar, PathTracing) {
  expectRendersWithTextures(Algorithm::PathTracing, 32);
}
TEST(VeachAjar, Bidirectional) {
  expectRendersWithTextures(Algorithm::Bidirectional, 8);
}
TEST(VeachAjar, Pssmlt) {
  expectRendersWithTextures(Algorithm::PSSMLT, 16);
}
TEST(VeachAjar, PssmltOverPathTracing) {
  expectRendersWithTextures(Algorithm::PSSMLTOverPT, 32);
}
// The Markov chains need more work than the samplers before every seed shows the picture: at
// mmlt 128 and mlt 16 per pixel about one seed in five leaves its top and bottom alike (the
// chains that reach it are few), at these counts none of seeds 7..12 does.
TEST(VeachAjar, Multiplexed) {
  expectRendersWithTextures(Algorithm::MMLT, 512);
}
TEST(VeachAjar, PathSpace) {
  expectRendersWithTextures(Algorithm::MLT, 128);
}
TEST(VeachAjar, EnergyRedistribution) {
  expectRendersWithTextures(Algorithm::ERPT, 1);
}

}  // namespace
}  // namespace farm
