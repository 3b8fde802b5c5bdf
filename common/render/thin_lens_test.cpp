// A thin lens (tests/data/thin-lens: focused at 4 units; a checkerboard there fills the left
// half of the view, one three times as far, with squares larger than the blur, the right half):
//  - path tracing and BDPT agree within their variance. BDPT's light-tracing strategies (t = 1)
//    connect to the lens point its camera subpath sampled, and its MIS densities use it;
//  - the in-focus board is as sharp as through a pinhole and the far one blurred. Sharpness is
//    the product of two independent renders' horizontal pixel differences, averaged over a
//    region: its expectation is the squared gradient of the expected image, noise cancels.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "common/mcmc/primary_sample_integrand.h"
#include "common/render/image_agreement.h"
#include "common/render/local_render.h"
#include "common/sampling/rng.h"
#include "common/sampling/sampler.h"
#include "common/scene/loaders/scene_files.h"
#include "common/scene/scene.h"
#include "common/transport/bidirectional.h"

namespace farm {
namespace {

const std::string kScene = std::string(FARM_TEST_DATA_DIR) + "/thin-lens/scene.pbrt";

Image render(Algorithm algorithm, int64_t spp, uint64_t seed, float lensRadius = -1,
             const std::string& file = kScene) {
  RenderSettings s;
  s.algorithm = algorithm;
  s.samplesPerPixel = spp;
  s.seed = seed;
  auto scene = loadScene(file, s);
  if (lensRadius >= 0) {
    SceneDescription d = scene->description();
    d.camera.lensRadius = lensRadius;
    scene = std::make_shared<Scene>(d);
  }
  RenderJob job(scene, s, "thin-lens");
  return renderLocally(job).image;
}

TEST(ThinLens, PathTracingAndBidirectionalAgree) {
  Image pt[2] = {render(Algorithm::PathTracing, 64, 1), render(Algorithm::PathTracing, 64, 2)};
  Image bd[2] = {render(Algorithm::Bidirectional, 16, 3), render(Algorithm::Bidirectional, 16, 4)};
  ASSERT_EQ(pt[0].rgb.size(), size_t(64 * 32 * 3));
  const Agreement g = compare(pt, bd);
  EXPECT_NEAR(g.meanA, g.meanB, 4 * g.se);
  // The ratio's spread over 6000 pixels is a few percent; 1.3 leaves room for the variance
  // estimates' own noise.
  EXPECT_LT(g.ratio, 1.3);
  std::printf(
      "thin lens: means pt %.4f bdpt %.4f (se %.4f), squared differences over variance "
      "%.3f\n",
      g.meanA, g.meanB, g.se, g.ratio);
}

// Light tracing alone against next-event estimation alone, each unweighted, on the paths of two
// edges (light, surface, lens): the two estimate the same image, one through the lens point its
// connection picked, the other through the camera ray's. With MIS the light-tracing strategy
// has little weight in this scene, so the comparison above would not see it wrong.
TEST(ThinLens, LightTracingThroughTheLensAgreesWithNextEventEstimation) {
  RenderSettings settings;
  auto scene = loadScene(kScene, settings);
  const Camera& camera = scene->camera();
  ASSERT_TRUE(camera.hasLens());
  BidirectionalTracer tracer(*scene, 2);
  const int w = camera.width(), h = camera.height();
  const int64_t samples = int64_t(w) * h * 200;
  // [strategy][render]: per pixel sums of the unweighted splats.
  std::vector<double> image[2][2];
  for (auto& strategy : image)
    for (auto& r : strategy) r.assign(size_t(w) * h, 0.0);
  for (int r = 0; r < 2; ++r) {
    Rng rng(77 + r, 5);
    IndependentSampler sampler(&rng);
    for (int64_t i = 0; i < samples; ++i) {
      tracer.visitStrategies(primarySampleFilmPoint(camera, sampler), sampler,
                             [&](const BidirectionalTracer::StrategyPath& p) {
                               if (p.s + p.t != 3 || p.s == 0) return;
                               const int which = p.t == 1 ? 0 : 1;
                               const int x = int(p.film.x), y = int(p.film.y);
                               if (x < 0 || y < 0 || x >= w || y >= h) return;
                               image[which][r][size_t(y) * w + x] += p.unweighted.x;
                             });
    }
  }
  double squared = 0, variance = 0, total[2] = {0, 0};
  for (size_t j = 0; j < image[0][0].size(); ++j) {
    double est[2], var[2];
    for (int k = 0; k < 2; ++k) {
      const double a = image[k][0][j] / double(samples), b = image[k][1][j] / double(samples);
      est[k] = 0.5 * (a + b);
      var[k] = (a - b) * (a - b) / 4;
      total[k] += est[k];
    }
    squared += (est[0] - est[1]) * (est[0] - est[1]);
    variance += var[0] + var[1];
  }
  const double ratio = squared / variance;
  std::printf(
      "thin lens, two-edge paths: light tracing %.4f, next-event %.4f (image sums), "
      "squared differences over variance %.3f\n",
      total[0], total[1], ratio);
  EXPECT_GT(total[0], 0);
  EXPECT_LT(ratio, 1.3);
}

// The primary-sample chains over BDPT and over PT, and multiplexed MLT, reach the lens through
// their tracers' two extra camera numbers, path-space MLT and ERPT through their paths' camera
// vertices: their images against path tracing over kRenders independent renders each
// (expectRendersAgree: the means' error from the renders' spread holds whatever correlates a
// render's pixels: a chain's path, ERPT's deposits around a seed, the Z that scales it).
constexpr int kRenders = 16;

Image renderChain(Algorithm algorithm, int64_t mpp, uint64_t seed, const std::string& file) {
  RenderSettings s;
  s.algorithm = algorithm;
  s.mutationsPerPixel = mpp;
  if (algorithm == Algorithm::ERPT) {
    // Its seeds are path tracing's, the chains only move their energy: per seed, as many
    // steps as the others' mutations per pixel.
    s.samplesPerPixel = mpp / 4;
    s.erptLength = 16;
  }
  s.seed = seed;
  auto scene = loadScene(file, s);
  EXPECT_TRUE(scene->camera().hasLens());
  RenderJob job(scene, s, "thin-lens");
  return renderLocally(job).image;
}

// Path tracing's kRenders renders of a scene file at `spp`, rendered once for every test that
// compares with them.
const std::vector<Image>& pathTraced(const std::string& file, int64_t spp) {
  static std::map<std::pair<std::string, int64_t>, std::vector<Image>> renders;
  std::vector<Image>& r = renders[{file, spp}];
  for (int k = int(r.size()); k < kRenders; ++k)
    r.push_back(render(Algorithm::PathTracing, spp, 21 + 2 * uint64_t(k), -1, file));
  return r;
}

void expectChainAgreesWithPathTracing(Algorithm algorithm, int64_t mpp,
                                      const std::string& file = kScene, int64_t ptSpp = 64) {
  std::vector<Image> chain;
  for (int k = 0; k < kRenders; ++k)
    chain.push_back(renderChain(algorithm, mpp, 31 + uint64_t(k), file));
  expectRendersAgree(std::string("thin lens ") + algorithmName(algorithm), pathTraced(file, ptSpp),
                     chain);
}

TEST(ThinLens, PssmltAgreesWithPathTracing) {
  expectChainAgreesWithPathTracing(Algorithm::PSSMLT, 64);
}
TEST(ThinLens, PssmltOverPathTracingAgreesWithPathTracing) {
  expectChainAgreesWithPathTracing(Algorithm::PSSMLTOverPT, 64);
}
TEST(ThinLens, MultiplexedAgreesWithPathTracing) {
  expectChainAgreesWithPathTracing(Algorithm::MMLT, 64);
}

// Path-space MLT moves the lens point with its bidirectional and lens subpath mutations (a new
// point on the lens when they regrow the camera's end); ERPT's perturbations keep each seed's,
// which path tracing drew, and need only keep the target (Cline et al. 2005).
TEST(ThinLens, PathSpaceMltAgreesWithPathTracing) {
  expectChainAgreesWithPathTracing(Algorithm::MLT, 64);
}
TEST(ThinLens, EnergyRedistributionAgreesWithPathTracing) {
  expectChainAgreesWithPathTracing(Algorithm::ERPT, 64);
}

// A light in view, out of focus: path-space MLT renders the light it sees directly in its
// chains here (its separate sampler of those paths projects through a pinhole, which would
// draw the light sharp), and agrees with path tracing on the blurred disc.
TEST(ThinLens, PathSpaceMltBlursALightInView) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "farm_thin_lens_light.pbrt").string();
  std::ofstream(path)
      << "LookAt 0 0 0  0 0 1  0 1 0\n"
         "Camera \"perspective\" \"float fov\" [ 30 ] \"float lensradius\" [ 0.3 ] "
         "\"float focaldistance\" [ 2 ]\n"
         "Film \"image\" \"integer xresolution\" [ 32 ] \"integer yresolution\" [ 32 ]\n"
         "PixelFilter \"box\"\nIntegrator \"path\" \"integer maxdepth\" [ 2 ]\nWorldBegin\n"
         "Material \"matte\" \"rgb Kd\" [ 0.5 0.5 0.5 ]\n"
         "Shape \"trianglemesh\" \"integer indices\" [ 0 1 2  0 2 3 ] "
         "\"point P\" [ -9 -9 12   9 -9 12   9 9 12   -9 9 12 ]\n"
         "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 4 4 4 ]\n"
         "Shape \"trianglemesh\" \"integer indices\" [ 0 2 1  0 3 2 ] "
         "\"point P\" [ -0.4 -0.4 6   0.4 -0.4 6   0.4 0.4 6   -0.4 0.4 6 ]\nAttributeEnd\n";
  expectChainAgreesWithPathTracing(Algorithm::MLT, 256, path, 256);
  std::filesystem::remove(path);
}

// Mean product of the two renders' horizontal differences over columns [x0, x1).
double sharpness(const Image& a, const Image& b, int x0, int x1) {
  double sum = 0;
  int count = 0;
  for (int y = 2; y < a.height - 2; ++y) {
    for (int x = x0; x + 1 < x1; ++x) {
      sum += double(a.at(x + 1, y).x - a.at(x, y).x) * double(b.at(x + 1, y).x - b.at(x, y).x);
      ++count;
    }
  }
  return sum / count;
}

TEST(ThinLens, InFocusPlaneIsSharperThanTheFarOne) {
  Image a = render(Algorithm::PathTracing, 32, 11), b = render(Algorithm::PathTracing, 32, 12);
  const double near = sharpness(a, b, 2, 30), far = sharpness(a, b, 34, 62);
  // Each board against itself through a pinhole: the lens alone makes the difference.
  Image pa = render(Algorithm::PathTracing, 32, 13, 0),
        pb = render(Algorithm::PathTracing, 32, 14, 0);
  const double pinholeNear = sharpness(pa, pb, 2, 30), pinholeFar = sharpness(pa, pb, 34, 62);
  std::printf("sharpness: lens near %.4f far %.4f; pinhole near %.4f far %.4f\n", near, far,
              pinholeNear, pinholeFar);
  EXPECT_GT(near, 0.7 * pinholeNear);  // in focus: as sharp as through the pinhole, nearly
  EXPECT_LT(far, 0.3 * pinholeFar);    // edges blurred over about 8 pixels
}

}  // namespace
}  // namespace farm
