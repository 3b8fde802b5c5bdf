// The stability suite: every algorithm on stiff and extreme scenes that the tests write
// themselves (common/scene/stiff_scenes.h), each with a known answer or an exact equivalence.
//
// For each case and algorithm, kRenders independent renders (own seeds, own bootstraps) give
// the image mean over the case's pixels; their spread gives its standard error, so the bound
// comes from the estimator's own variance, with every source of it (Z's included), and not from
// the answer. The deviation from the known answer, in standard errors, must stay below Student's
// t for kRenders - 1 degrees of freedom at 1e-4 two-sided; where the answer is itself rendered
// (an equivalent scene, by BDPT), its standard error adds. The renders must also be precise
// enough to tell a few per cent (relative standard error at most kMaxRelativeError), finite and
// non-negative, and nothing may have been rejected as invalid. Each case prints its row of the
// suite's table (case, algorithm, deviation in standard errors, relative standard error,
// invalid splats, seconds).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/math/statistics.h"
#include "common/render/local_render.h"
#include "common/scene/loaders/mitsuba_loader.h"
#include "common/scene/scene.h"
#include "common/scene/stiff_scenes.h"

namespace farm {
namespace {

constexpr int kRenders = 16;
constexpr double kMaxRelativeError = 0.01;

// Work per render for each algorithm, at a cost of the same order.
RenderSettings settingsFor(Algorithm a, double work, uint64_t seed) {
  RenderSettings s;
  s.algorithm = a;
  s.seed = seed;
  s.samplesPerPixel = int64_t(std::ceil((a == Algorithm::Bidirectional ? 4 : 8) * work));
  s.mutationsPerPixel = int64_t(std::ceil(8 * work));
  if (a == Algorithm::ERPT) {
    s.samplesPerPixel = int64_t(std::ceil(8 * work));  // its pixels are the noisiest
    s.erptLength = 16;
  }
  // The Markov chains' image means are Z's: their precision is the bootstrap's. A multiplexed
  // candidate (one strategy of one length) is cheap and noisy: four times as many.
  s.bootstrapSamples = int64_t(std::ceil(work)) << (a == Algorithm::MMLT ? 15 : 13);
  s.numChains = 16;
  return s;
}

constexpr int kBlocks = 4;  // the image is compared as a whole and in kBlocks x kBlocks blocks
constexpr int kStatistics = 1 + kBlocks * kBlocks;

// Statistic 0: the image mean of (r + g + b) / 3; 1 + j: the mean over block j. The whole
// image's mean catches a bias in Z or everywhere; but a Markov chain's splats all carry Z / N,
// so its image mean is Z's whatever the chain does, and only where the splats land (the blocks)
// shows whether the chain samples the right distribution.
std::vector<double> statistics(const Image& img) {
  std::vector<double> sum(kStatistics, 0.0), count(kStatistics, 0.0);
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const float* p = &img.rgb[3 * (size_t(y) * img.width + x)];
      const double v = (double(p[0]) + p[1] + p[2]) / 3;
      const int block = 1 + (y * kBlocks / img.height) * kBlocks + x * kBlocks / img.width;
      sum[0] += v, count[0] += 1;
      sum[size_t(block)] += v, count[size_t(block)] += 1;
    }
  }
  for (int i = 0; i < kStatistics; ++i) sum[size_t(i)] /= std::max(1.0, count[size_t(i)]);
  return sum;
}

struct Outcome {
  std::vector<double> mean, se;  // of each statistic over kRenders renders
  int64_t invalid = 0;           // splats rejected as NaN, infinite or negative
  int64_t badPixels = 0;         // non-finite or negative pixels in the images
  double seconds = 0;
};

Outcome renderStatistics(const std::shared_ptr<Scene>& scene, Algorithm a, double work,
                         uint64_t seedBase) {
  Outcome o;
  std::vector<std::vector<double>> perRender(kStatistics);
  for (int k = 0; k < kRenders; ++k) {
    RenderJob job(scene, settingsFor(a, work, seedBase + uint64_t(k)), "stiff");
    LocalRenderResult r = renderLocally(job);
    o.invalid += r.rejected.total();
    o.seconds += r.seconds;
    for (float v : r.image.rgb) o.badPixels += !(std::isfinite(v) && v >= 0);
    const std::vector<double> st = statistics(r.image);
    for (int i = 0; i < kStatistics; ++i) perRender[size_t(i)].push_back(st[size_t(i)]);
  }
  for (const std::vector<double>& x : perRender) {
    const MeanEstimate e = meanOfIndependent(x);
    o.mean.push_back(e.mean);
    o.se.push_back(e.standardError);
  }
  return o;
}

// The answer for each statistic; se 0 where it is analytic.
struct KnownAnswer {
  std::vector<double> mean, se;
};

struct StiffCase {
  std::string name;
  SceneDescription scene;
  double work = 1;  // multiplies settingsFor's counts
  // The answer: analytic, or rendered from an equivalent scene.
  std::function<KnownAnswer(const Scene&)> answer;
  double precision = kMaxRelativeError;  // the largest relative standard error that can tell
};

void runCase(const StiffCase& c) {
  auto scene = std::make_shared<Scene>(c.scene);
  const KnownAnswer known = c.answer(*scene);
  // Two-sided 1e-4 for the whole image; Bonferroni over the blocks.
  const double limit = studentQuantile(kRenders - 1, 1 - 0.5e-4);
  const double blockLimit = studentQuantile(kRenders - 1, 1 - 0.5e-4 / (kBlocks * kBlocks));
  std::printf("%-26s %-10s %9s %9s %9s %8s %8s\n", "case", "algorithm", "dev (SE)", "max block",
              "rel SE", "invalid", "seconds");
  for (Algorithm a : allAlgorithms()) {
    Outcome o = renderStatistics(scene, a, c.work, 7919);
    std::vector<double> deviation(kStatistics);
    double worstBlock = 0;
    for (int i = 0; i < kStatistics; ++i) {
      const double se = std::hypot(o.se[size_t(i)], known.se[size_t(i)]);
      const double diff = o.mean[size_t(i)] - known.mean[size_t(i)];
      deviation[size_t(i)] = se > 0 ? diff / se : (diff == 0 ? 0 : INFINITY);
      if (i > 0 && std::abs(deviation[size_t(i)]) > std::abs(worstBlock))
        worstBlock = deviation[size_t(i)];
    }
    std::printf("%-26s %-10s %9.2f %9.2f %8.3f%% %8lld %8.2f\n", c.name.c_str(), algorithmName(a),
                deviation[0], worstBlock, 100 * o.se[0] / known.mean[0], (long long)o.invalid,
                o.seconds);
    std::fflush(stdout);
    EXPECT_LT(std::abs(deviation[0]), limit)
        << c.name << " " << algorithmName(a) << ": mean " << o.mean[0] << " +- " << o.se[0]
        << ", expected " << known.mean[0] << " +- " << known.se[0];
    for (int i = 1; i < kStatistics; ++i) {
      EXPECT_LT(std::abs(deviation[size_t(i)]), blockLimit)
          << c.name << " " << algorithmName(a) << " block " << i - 1 << ": mean "
          << o.mean[size_t(i)] << " +- " << o.se[size_t(i)] << ", expected "
          << known.mean[size_t(i)] << " +- " << known.se[size_t(i)];
    }
    EXPECT_LE(o.se[0], c.precision * known.mean[0])
        << c.name << " " << algorithmName(a) << ": too noisy to tell a bias";
    EXPECT_EQ(o.invalid, 0) << c.name << " " << algorithmName(a);
    EXPECT_EQ(o.badPixels, 0) << c.name << " " << algorithmName(a);
  }
}

// The furnace's radiance, the same at every pixel.
std::function<KnownAnswer(const Scene&)> furnaceAnswer(const Spectrum& le, int maxDepth) {
  return [le, maxDepth](const Scene&) {
    Spectrum l = stiff::furnaceRadiance(le, stiff::kFurnaceAlbedo, maxDepth);
    return KnownAnswer{std::vector<double>(kStatistics, (double(l.x) + l.y + l.z) / 3),
                       std::vector<double>(kStatistics, 0.0)};
  };
}

// The answer rendered (by BDPT unless said, with more work and its own seeds) from an
// equivalent scene, once however many cases share it.
std::function<KnownAnswer(const Scene&)> renderedAnswer(
    SceneDescription equivalent, double work, Algorithm algorithm = Algorithm::Bidirectional) {
  auto rendered = std::make_shared<std::optional<KnownAnswer>>();
  return [equivalent, work, algorithm, rendered](const Scene&) {
    if (!*rendered) {
      Outcome o = renderStatistics(std::make_shared<Scene>(equivalent), algorithm, work, 104729);
      *rendered = KnownAnswer{o.mean, o.se};
    }
    return **rendered;
  };
}

TEST(StiffSuite, FurnaceUnitScale) {
  runCase({"furnace box", stiff::furnaceBox(1, 4), 1, furnaceAnswer(stiff::kFurnaceLe, 4)});
}

// Scale invariance: the same furnace 1e4 and 1e-4 times the size, camera moved to match.
TEST(StiffSuite, FurnaceScaled) {
  runCase({"furnace box x1e4", stiff::furnaceBox(1e4f, 4), 1, furnaceAnswer(stiff::kFurnaceLe, 4)});
  runCase(
      {"furnace box x1e-4", stiff::furnaceBox(1e-4f, 4), 1, furnaceAnswer(stiff::kFurnaceLe, 4)});
}

// Radiance of 1e9 and 1e-9: nothing overflows or underflows on the way to the image.
TEST(StiffSuite, FurnaceExtremeRadiance) {
  runCase({"furnace Le 1e9", stiff::furnaceBox(1, 4, stiff::kFurnaceLe * 1e9f), 1,
           furnaceAnswer(stiff::kFurnaceLe * 1e9f, 4)});
  runCase({"furnace Le 1e-9", stiff::furnaceBox(1, 4, stiff::kFurnaceLe * 1e-9f), 1,
           furnaceAnswer(stiff::kFurnaceLe * 1e-9f, 4)});
}

// Grazing cameras and grazing lights: a furnace 200 times wider than thick.
TEST(StiffSuite, FlatFurnaceGrazing) {
  runCase({"flat furnace (grazing)", stiff::flatFurnace(0.01f, 4), 1,
           furnaceAnswer(stiff::kFurnaceLe, 4)});
}

// 10^5 emitting triangles, areas over ten decades, in 48 lights of powers over four.
TEST(StiffSuite, TessellatedFurnace) {
  runCase({"furnace 1e5 triangles", stiff::tessellatedFurnace(8, 1042, 4), 1,
           furnaceAnswer(stiff::kFurnaceLe, 4)});
}

// Glass in the furnace: index 1.0001 (a slab that must render as no slab) and 4.
TEST(StiffSuite, GlassInFurnace) {
  runCase({"furnace glass ior 1.0001", stiff::glassInFurnace(1.0001f), 4,
           furnaceAnswer(stiff::kFurnaceLe, -1)});
  // Held to 3%: PSSMLT over path tracing takes its Z from path-traced candidates, whose
  // light through index-4 glass comes in rare large samples.
  runCase({"furnace glass ior 4", stiff::glassInFurnace(4.0f), 6,
           furnaceAnswer(stiff::kFurnaceLe, -1), 0.03});
}

// The camera inside a glass ball in the furnace sees ior^2 times the furnace's radiance: what
// tells a missing or misplaced n^2 (seen from outside the glass, it cancels).
TEST(StiffSuite, CameraInGlass) {
  runCase({"camera in glass ior 1.5", stiff::cameraInGlassBall(1.5f), 2,
           furnaceAnswer(stiff::kFurnaceLe * (1.5f * 1.5f), -1)});
}

// The furnace from an OBJ holding degenerate triangles, through the loader: they are left out
// with a warning, and what is left is exactly the clean mesh.
TEST(StiffSuite, DegenerateTriangles) {
  SceneDescription clean = loadMitsubaScene(stiff::furnaceBoxFile(false, 4));
  SceneDescription dirty = loadMitsubaScene(stiff::furnaceBoxFile(true, 4));
  EXPECT_TRUE(clean.warnings.empty());
  ASSERT_EQ(dirty.warnings.size(), 1u);
  EXPECT_NE(dirty.warnings[0].find("walls.obj': 5 degenerate triangles left out (2 "
                                   "repeated-vertex, 2 collinear (zero-area), 1 needle)"),
            std::string::npos)
      << dirty.warnings[0];
  ASSERT_EQ(dirty.shapes.size(), 1u);
  EXPECT_EQ(dirty.shapes[0].indices.size(), clean.shapes[0].indices.size());
  runCase({"furnace degenerate tris", dirty, 1, furnaceAnswer(stiff::kFurnaceLe, 4)});
}

// The furnace from a binary PLY, through the loader and Open Asset Import Library: the same mesh
// as the OBJ, and the furnace's answer.
TEST(StiffSuite, FurnaceFromPly) {
  SceneDescription obj = loadMitsubaScene(stiff::furnaceBoxFile(false, 4));
  SceneDescription ply = loadMitsubaScene(stiff::furnaceBoxFile(false, 4, true));
  ASSERT_EQ(ply.shapes.size(), 1u);
  EXPECT_EQ(ply.shapes[0].indices.size(), obj.shapes[0].indices.size());
  EXPECT_TRUE(ply.warnings.empty());
  runCase({"furnace from ply", ply, 1, furnaceAnswer(stiff::kFurnaceLe, 4)});
}

// A floor lit by a sphere 100 radii away near its horizon (light arriving 1.2 degrees above
// the floor) and seen from 0.5 degrees above it: rho Le r^2 cos(theta) / d^2, direct light.
TEST(StiffSuite, GrazingFloor) {
  stiff::FloorLight f;
  f.center = Vec3f(25, 0.6f, 0);
  f.radius = 0.25f;
  f.le = 4e3f;
  const Vec3f eye(-2, 0.05f, 0.3f), at(4, 0, 0);
  SceneDescription d = stiff::floorUnderSphere(f, eye, at, 0.3f, 8);
  // The analytic radiance averaged over each pixel (a box filter) on a g x g grid: an image.
  auto answer = [f](const Scene& scene) {
    const Camera& cam = scene.camera();
    const int g = 8;
    Image expected(cam.width(), cam.height());
    for (int y = 0; y < cam.height(); ++y) {
      for (int x = 0; x < cam.width(); ++x) {
        double sum = 0;
        for (int j = 0; j < g; ++j) {
          for (int i = 0; i < g; ++i) {
            Ray ray = cam.generateRay(Vec2f(x + (i + 0.5f) / g, y + (j + 0.5f) / g));
            if (!(ray.d.y < 0)) ADD_FAILURE() << "a camera ray misses the floor";
            Vec3f p = ray.o + ray.d * (-ray.o.y / ray.d.y);
            sum += stiff::floorRadiance(f, p);
          }
        }
        float* px = &expected.rgb[3 * (size_t(y) * cam.width() + x)];
        px[0] = px[1] = px[2] = float(sum / (g * g));
      }
    }
    return KnownAnswer{statistics(expected), std::vector<double>(kStatistics, 0.0)};
  };
  runCase({"grazing floor", d, 6, answer});
}

// A sphere 1e-4 of the area (radius 1/100) at the same power irradiates as the large one:
// the same image, the light out of view. (The large one is small too: a black sphere of radius
// 0.05 would shade the ceiling around it by 0.5% of the image.)
TEST(StiffSuite, TinyLight) {
  stiff::Room tiny, large;
  large.lightRadius = 0.005f;
  tiny.lightRadius = 0.00005f;
  tiny.plate = large.plate = false;
  runCase({"tiny light (1e-4 area)", stiff::room(tiny), 2, renderedAnswer(stiff::room(large), 16)});
}

// The room with a thin plate 0.01 above its floor, scaled by 1e4 and 1e-4: the image of the
// room at scale 1 (a shadow ray trimmed by a fraction of its length would let light under the
// plate).
TEST(StiffSuite, RoomScaled) {
  stiff::Room unit, big, small;
  big.scale = 1e4f;
  small.scale = 1e-4f;
  const auto unitRoom = renderedAnswer(stiff::room(unit), 16);
  runCase({"room x1e4", stiff::room(big), 2, unitRoom});
  runCase({"room x1e-4", stiff::room(small), 2, unitRoom});
}

// Shading normals 50 degrees from the geometric normal: every algorithm agrees with path
// tracing, which follows camera paths only (the adjoint BSDF's correction, Veach 1997 eq. 5.17,
// is what makes light paths agree with them).
TEST(StiffSuite, TiltedShadingNormals) {
  stiff::Room r;
  r.tiltedNormals = true;
  runCase({"tilted shading normals", stiff::room(r), 2,
           renderedAnswer(stiff::room(r), 64, Algorithm::PathTracing)});
}

// A coarse glass ball with smooth shading normals on the floor under the light, under either
// convention: its caustic on the floor, the floor seen through it and, under the lax convention
// (--shading-normals lax: Mitsuba without strictNormals, Tungsten, pbrt-v4), the paths near its
// faces' edges whose directions the two normals put on different sides of the surface, which
// strict normals drop (3.5% of this image; the water caustic's kind of path). Every algorithm
// estimates path tracing's image. (On the tilted floor of TiltedShadingNormals the conventions
// give the same image: a diffuse surface reflects nothing to a direction below its shading
// normal, and one below its geometric normal leaves the room.)
TEST(StiffSuite, SmoothShadedGlassBall) {
  stiff::Room r;
  r.ballIor = 1.5f;
  r.plate = false;
  r.lightRadius = 0.3f;
  for (bool strict : {true, false}) {
    SceneDescription d = stiff::room(r, 16, 6);
    d.camera.fovDegrees = 30;  // the ball fills most of the view
    d.strictNormals = strict;
    runCase({strict ? "smooth glass ball, strict" : "smooth glass ball, lax", d, 2,
             renderedAnswer(d, 64, Algorithm::PathTracing)});
  }
}

// A light in a closed box with a small hole (a sixth of the housing's side): under a per cent
// of its light gets out, much of it after bouncing inside (Z small, its paths long and rare).
// Held to 5%: every algorithm is slow here, which is what the case is about.
TEST(StiffSuite, NearlySealedLight) {
  stiff::Room r;
  r.sealedHole = 0.05f;
  r.plate = false;
  runCase({"nearly sealed light", stiff::room(r), 16, renderedAnswer(stiff::room(r), 64), 0.05});
}

// Roughness at its stiff end: a rough conductor at alpha 1e-4 renders as the smooth one; and the
// smooth one (a Dirac lobe, which the path-space mutations see through specularLobe and cross
// with perturbations) renders alike with every algorithm.
TEST(StiffSuite, RoughConductorAtTheStiffEnd) {
  const auto mirror =
      renderedAnswer(stiff::room(stiff::metalPlateRoom(BsdfDescription::Type::Conductor, 0)), 16);
  runCase({"rough metal a=1e-4",
           stiff::room(stiff::metalPlateRoom(BsdfDescription::Type::RoughConductor, 1e-4f)), 4,
           mirror});
  runCase({"smooth metal", stiff::room(stiff::metalPlateRoom(BsdfDescription::Type::Conductor, 0)),
           4, mirror});
}

// Roughness from glossy to rough: every algorithm agrees with path tracing.
TEST(StiffSuite, RoughConductorGlossyToRough) {
  for (float alpha : {0.01f, 1.0f}) {
    SceneDescription d =
        stiff::room(stiff::metalPlateRoom(BsdfDescription::Type::RoughConductor, alpha));
    runCase({"rough metal a=" + std::to_string(alpha).substr(0, 4), d, 2,
             renderedAnswer(d, 64, Algorithm::PathTracing)});
  }
}

// A rough glass slab in the furnace: lossless at alpha 1e-4 (the furnace's answer); at alpha 1
// microfacet shadowing loses light, and every algorithm agrees with path tracing.
TEST(StiffSuite, RoughGlassInFurnace) {
  runCase({"furnace rough glass 1e-4", stiff::glassInFurnace(1.5f, 16, 1e-4f), 2,
           furnaceAnswer(stiff::kFurnaceLe, -1)});
  SceneDescription rough = stiff::glassInFurnace(1.5f, 16, 1.0f);
  runCase({"furnace rough glass 1", rough, 2, renderedAnswer(rough, 32, Algorithm::PathTracing)});
}

// A slab of index 1.0001 in front of the camera renders as no slab: every camera ray crosses
// it, light-tracing strategies cannot reach the camera through it, and MIS must give its paths
// to the strategies that can.
TEST(StiffSuite, IndexMatchedSlab) {
  stiff::Room slab, none;
  slab.slabIor = 1.0001f;
  // Unbounded paths: the slab adds two edges to every camera path.
  runCase({"slab ior 1.0001", stiff::room(slab, 16, -1), 2,
           renderedAnswer(stiff::room(none, 16, -1), 16)});
}

// A light half covered by a black plate 1e-4 below it: the image of the light's other half
// alone. Shadow rays stopping a fraction of their length short of the light (1e-4 of about 2)
// would miss the plate and let the covered half shine.
TEST(StiffSuite, CoveredLight) {
  runCase({"light covered 1e-4 below", stiff::coveredLightRoom(true), 2,
           renderedAnswer(stiff::coveredLightRoom(false), 16)});
}

// No light at all (Z = 0): the path tracers render black, the algorithms that need Z refuse
// with a clear message; nothing NaN.
TEST(StiffSuite, NoLight) {
  auto scene = std::make_shared<Scene>(stiff::unlitRoom());
  for (Algorithm a : allAlgorithms()) {
    RenderJob job(scene, settingsFor(a, 1, 1), "unlit");
    if (needsBootstrap(a)) {
      try {
        renderLocally(job);
        ADD_FAILURE() << algorithmName(a) << " rendered a scene without light";
      } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("no light reaches the camera"), std::string::npos)
            << algorithmName(a) << ": " << e.what();
      }
      continue;
    }
    LocalRenderResult r = renderLocally(job);
    EXPECT_EQ(r.rejected.total(), 0);
    for (float v : r.image.rgb) ASSERT_EQ(v, 0.0f) << algorithmName(a);
  }
}

}  // namespace
}  // namespace farm
