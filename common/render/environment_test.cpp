// Environment lights through every algorithm that takes them. Analytic: under a constant sky of
// radiance Le, diffuse surfaces of albedo 1 have radiance Le everywhere whatever their shape
// (the white furnace: L = Le solves the rendering equation), and a lone convex diffuse sphere
// of albedo rho has rho Le (each of its points sees only sky). Under an image sky, path tracing,
// BDPT and the chains agree within their variance. Tolerances come from the estimators' own
// spread (furnace_test.cpp explains the pixel statistics; image_agreement.h the comparison).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <vector>

#include "common/plan/scene_analysis.h"
#include "common/render/image_agreement.h"
#include "common/render/local_render.h"
#include "common/scene/bsdfs/coating_transmittance.h"
#include "common/scene/loaders/scene_files.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"

namespace farm {
namespace {

const Spectrum kSky(1.0f, 0.5f, 2.0f);

// A camera at the origin looking down +z (or -z, at nothing but sky) at a large sphere that
// fills its view, and optionally a small one in front of it that the two reflect between.
// coated: the spheres are white under a clear coat of roughness 1e-3 (Mitsuba's roughplastic),
// which loses no energy either: what the coat does not reflect, the base returns through it.
SceneDescription skyFurnace(float albedo, bool smallSphere, bool lookAway = false,
                            bool coated = false) {
  SceneDescription d;
  d.camera.toWorld = lookAway ? Matrix4::rotate(Vec3f(0, 1, 0), 180) : Matrix4::identity();
  d.camera.fovDegrees = 60;
  d.camera.width = d.camera.height = 24;
  BsdfDescription b;
  b.reflectance = Spectrum(albedo);
  if (coated) {
    b.type = BsdfDescription::Type::CoatedDiffuse;
    b.distribution = MicrofacetDistribution::GGX;
    b.alpha = 1e-3f;
    b.intIOR = 1.5f;
    b.extIOR = 1;
    b.coating = sharedCoatingTransmittance(b.distribution, b.alpha, b.intIOR);
  }
  d.bsdfs.push_back(b);
  d.shapes.push_back(sphereShape(Vec3f(0, 0, 6), 4.5f, 0));  // 48.6 degrees wide: the whole view
  if (smallSphere) d.shapes.push_back(sphereShape(Vec3f(0.3f, 0.2f, 1.1f), 0.25f, 0));
  d.environment.present = true;
  d.environment.scale = kSky;
  return d;
}

void expectUniformImage(Algorithm algorithm, const SceneDescription& desc, float factor,
                        const char* what) {
  RenderSettings settings;
  settings.algorithm = algorithm;
  settings.samplesPerPixel = algorithm == Algorithm::ERPT ? 16 : 64;
  settings.mutationsPerPixel = 64;
  settings.erptLength = 16;
  settings.seed = 17;
  settings.bootstrapSamples = 1 << 15;
  RenderJob job(std::make_shared<Scene>(desc), settings, "sky");
  LocalRenderResult r = renderLocally(job);
  const PixelStats st = pixelStats(r.image);
  for (int c = 0; c < 3; ++c) {
    const double expected = double(kSky[c]) * factor;
    double se = st.stdError[c];
    if (isMarkovChain(algorithm) && r.bootstrap.normalization > 0) {  // the image scales with Z
      const double zRel = std::sqrt(r.bootstrap.normalizationRelativeVariance(r.largeSteps));
      se = std::hypot(se, expected * zRel);
    }
    EXPECT_NEAR(st.mean[c], expected, 4 * se + 1e-6 * expected)
        << algorithmName(algorithm) << " " << what << " channel " << c;
  }
  EXPECT_EQ(r.rejected.total(), 0);
}

void expectSkyFurnaces(Algorithm algorithm) {
  expectUniformImage(algorithm, skyFurnace(1.0f, true), 1.0f, "white furnace of two spheres");
  expectUniformImage(algorithm, skyFurnace(0.6f, false), 0.6f, "lone sphere of albedo 0.6");
  expectUniformImage(algorithm, skyFurnace(0.6f, false, true), 1.0f, "the sky seen directly");
  expectUniformImage(algorithm, skyFurnace(1.0f, true, false, true), 1.0f,
                     "white furnace of two coated spheres");
}

TEST(Environment, ConstantSkyPathTracing) {
  expectSkyFurnaces(Algorithm::PathTracing);
}
TEST(Environment, ConstantSkyBidirectional) {
  expectSkyFurnaces(Algorithm::Bidirectional);
}
TEST(Environment, ConstantSkyPssmlt) {
  expectSkyFurnaces(Algorithm::PSSMLT);
}
TEST(Environment, ConstantSkyPssmltOverPathTracing) {
  expectSkyFurnaces(Algorithm::PSSMLTOverPT);
}
TEST(Environment, ConstantSkyMultiplexed) {
  expectSkyFurnaces(Algorithm::MMLT);
}
// Path-space chains end camera subpaths on the sky where their rays leave the scene, start
// light subpaths there, and connect to it along its direction.
TEST(Environment, ConstantSkyPathSpaceMlt) {
  expectSkyFurnaces(Algorithm::MLT);
}
TEST(Environment, ConstantSkyEnergyRedistribution) {
  expectSkyFurnaces(Algorithm::ERPT);
}

// A diffuse floor, a glossy (plastic) ball and a diffuse one on it, under the image sky with its
// sun behind the camera's left; the camera sees floor, balls and sky.
SceneDescription imageSkyScene(bool equalArea = false) {
  SceneDescription d;
  d.camera.toWorld = Matrix4::lookAt(Vec3f(0, 1.2f, -1), Vec3f(0, 0.2f, 3), Vec3f(0, 1, 0));
  d.camera.fovDegrees = 70;
  d.camera.width = 32;
  d.camera.height = 24;
  BsdfDescription floor;
  floor.reflectance = Spectrum(0.5f, 0.45f, 0.4f);
  floor.twoSided = true;
  d.bsdfs.push_back(floor);
  BsdfDescription plastic;
  plastic.type = BsdfDescription::Type::Plastic;
  plastic.reflectance = Spectrum(0.2f, 0.3f, 0.6f);
  plastic.distribution = MicrofacetDistribution::GGX;
  plastic.alpha = 0.15f;
  plastic.intIOR = 1.5f;
  plastic.extIOR = 1.0f;
  d.bsdfs.push_back(plastic);
  ShapeDescription ground;
  ground.positions = {{-4, 0, -2}, {4, 0, -2}, {4, 0, 8}, {-4, 0, 8}};
  ground.indices = {0, 2, 1, 0, 3, 2};
  ground.bsdf = 0;
  d.shapes.push_back(ground);
  d.shapes.push_back(sphereShape(Vec3f(-0.5f, 0.6f, 3), 0.6f, 1));
  d.shapes.push_back(sphereShape(Vec3f(0.9f, 0.4f, 2.4f), 0.4f, 0));
  d.environment.present = true;
  d.environment.image = equalArea ? equalAreaSky() : latLongSky(40);
  if (equalArea) d.environment.mapping = EnvironmentDescription::Mapping::EqualArea;
  d.environment.toWorld = Matrix4::rotate(Vec3f(1, 0, 0), -90);  // the map's z up is world y
  d.maxDepth = 6;
  return d;
}

Image renderSky(Algorithm algorithm, int64_t budget, uint64_t seed, bool equalArea = false) {
  RenderSettings s;
  s.algorithm = algorithm;
  s.samplesPerPixel = algorithm == Algorithm::ERPT ? std::max<int64_t>(budget / 8, 1) : budget;
  s.mutationsPerPixel = budget;
  s.erptLength = 16;  // ERPT: per seed, about as many steps as the others' mutations per pixel
  s.seed = seed;
  RenderJob job(std::make_shared<Scene>(imageSkyScene(equalArea)), s, "image-sky");
  LocalRenderResult r = renderLocally(job);
  EXPECT_EQ(r.rejected.total(), 0);
  return r.image;
}

// PT and BDPT under the image sky (lat-long or equal-area), each as two independent images.
void expectPathTracingAndBidirectionalAgree(bool equalArea) {
  Image pt[2] = {renderSky(Algorithm::PathTracing, 256, 1, equalArea),
                 renderSky(Algorithm::PathTracing, 256, 2, equalArea)};
  Image bd[2] = {renderSky(Algorithm::Bidirectional, 64, 3, equalArea),
                 renderSky(Algorithm::Bidirectional, 64, 4, equalArea)};
  const Agreement g = compare(pt, bd);
  EXPECT_GT(g.meanA, 0.05);
  EXPECT_NEAR(g.meanA, g.meanB, 4 * g.se);
  EXPECT_LT(g.ratio, 1.3);
  std::printf("%s sky: means pt %.4f bdpt %.4f (se %.4f), squared differences over variance %.3f\n",
              equalArea ? "equal-area" : "image", g.meanA, g.meanB, g.se, g.ratio);
}

TEST(Environment, ImageSkyPathTracingAndBidirectionalAgree) {
  expectPathTracingAndBidirectionalAgree(false);
}

// pbrt-v4's equal-area map, sampled and looked up through its own mapping.
TEST(Environment, EqualAreaSkyPathTracingAndBidirectionalAgree) {
  expectPathTracingAndBidirectionalAgree(true);
}

// A chain's image against path tracing's over kRenders independent renders each
// (expectRendersAgree: the means' error from the renders' spread holds whatever correlates a
// render's pixels: a chain's path, ERPT's deposits around a seed, the Z that scales it).
constexpr int kRenders = 16;

const std::vector<Image>& pathTracedSkies() {
  static const std::vector<Image> renders = [] {
    std::vector<Image> r;
    for (int k = 0; k < kRenders; ++k) r.push_back(renderSky(Algorithm::PathTracing, 256, 11 + k));
    return r;
  }();
  return renders;
}

void expectChainAgreesWithPathTracing(Algorithm algorithm) {
  std::vector<Image> chain;
  for (int k = 0; k < kRenders; ++k) chain.push_back(renderSky(algorithm, 128, 101 + k));
  expectRendersAgree(std::string("image sky ") + algorithmName(algorithm), pathTracedSkies(),
                     chain);
}

TEST(Environment, ImageSkyPssmltAgreesWithPathTracing) {
  expectChainAgreesWithPathTracing(Algorithm::PSSMLT);
}
TEST(Environment, ImageSkyPssmltOverPathTracingAgreesWithPathTracing) {
  expectChainAgreesWithPathTracing(Algorithm::PSSMLTOverPT);
}
TEST(Environment, ImageSkyMultiplexedAgreesWithPathTracing) {
  expectChainAgreesWithPathTracing(Algorithm::MMLT);
}
TEST(Environment, ImageSkyPathSpaceMltAgreesWithPathTracing) {
  expectChainAgreesWithPathTracing(Algorithm::MLT);
}
TEST(Environment, ImageSkyEnergyRedistributionAgreesWithPathTracing) {
  expectChainAgreesWithPathTracing(Algorithm::ERPT);
}

// The scene file's sky (tests/data/sky) through the loader and a whole render: the top rows
// see the blue sky, the bottom rows the floor under it; a map upside down or turned about the
// wrong axis would put its brown ground at the top.
TEST(Environment, SceneFileSkyIsAboveTheHorizon) {
  RenderSettings settings;
  settings.algorithm = Algorithm::Bidirectional;
  settings.samplesPerPixel = 16;
  settings.seed = 5;
  const std::string path = std::string(FARM_TEST_DATA_DIR) + "/sky/scene.pbrt";
  RenderJob job(loadScene(path, settings), settings, "sky");
  const Image image = renderLocally(job).image;
  ASSERT_EQ(image.width, 48);
  auto blueOverRed = [&](int y0, int y1) {
    double r = 0, b = 0;
    for (int y = y0; y < y1; ++y) {
      for (int x = 0; x < image.width; ++x) {
        r += image.rgb[3 * (size_t(y) * image.width + x)];
        b += image.rgb[3 * (size_t(y) * image.width + x) + 2];
      }
    }
    return b / r;
  };
  const double top = blueOverRed(0, 4), bottom = blueOverRed(image.height - 4, image.height);
  std::printf("sky scene: blue over red %.2f in the top rows, %.2f in the bottom ones\n", top,
              bottom);
  EXPECT_GT(top, 1.8);  // the map's sky near the horizon: 0.9 / 0.5
  EXPECT_LT(bottom, 1.5);
}

// Path-space chains take an environment in vacuum; with media too they refuse it, saying so.
TEST(Environment, PathSpaceChainsTakeItWithoutMedia) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "farm_environment_refused.pbrt").string();
  std::ofstream(path) << "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\n"
                         "WorldBegin\nShape \"sphere\"\nLightSource \"infinite\"\n";
  for (Algorithm algorithm : {Algorithm::MLT, Algorithm::ERPT}) {
    RenderSettings settings;
    settings.algorithm = algorithm;
    EXPECT_TRUE(loadScene(path, settings)->lights().environment()) << algorithmName(algorithm);
    SceneDescription withMedia;
    withMedia.environment.present = true;
    withMedia.media.push_back(MediumDescription());
    EXPECT_EQ(
        algorithmRefusal(withMedia, algorithm)
            .rfind(std::string("an environment light in a scene with media is not supported by ") +
                       algorithmName(algorithm),
                   0),
        0u)
        << algorithmRefusal(withMedia, algorithm);
  }
  RenderSettings pt;
  EXPECT_TRUE(loadScene(path, pt)->lights().environment());
  // Point lights and two-sided area lights they take.
  std::ofstream(path) << "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                         "LightSource \"point\"\nAttributeBegin\nAreaLightSource \"diffuse\" "
                         "\"bool twosided\" true\nShape \"sphere\"\nAttributeEnd\n";
  RenderSettings mlt;
  mlt.algorithm = Algorithm::MLT;
  EXPECT_EQ(loadScene(path, mlt)->lights().size(), 2u);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace farm
