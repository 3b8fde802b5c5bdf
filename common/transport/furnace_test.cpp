// Analytic answers for every estimator. A white furnace (a closed sphere that emits Le and
// reflects with albedo rho, seen from inside) has radiance Le (1 - rho^D) / (1 - rho) for paths
// of at most D edges everywhere; a diffuse floor under a spherical light has, at a point with
// distance d to the light's centre at height h, irradiance pi Le r^2 h / d^3 (the sphere is
// above the horizon). Tolerances come from the estimators' own variance: pixels of these
// images are independent estimates whose spread gives the standard error of their mean.
#include <gtest/gtest.h>

#include <cmath>

#include "common/math/statistics.h"
#include "common/render/image_agreement.h"
#include "common/render/local_render.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"
#include "common/transport/bidirectional.h"

namespace farm {
namespace {

void expectFurnace(Algorithm algorithm, int maxDepth) {
  const float albedo = 0.6f;
  SceneDescription desc = whiteFurnace(albedo, maxDepth);
  auto scene = std::make_shared<Scene>(desc);
  RenderSettings settings;
  settings.algorithm = algorithm;
  settings.samplesPerPixel = 64;
  settings.mutationsPerPixel = 64;
  settings.seed = 11;
  settings.bootstrapSamples = 1 << 15;
  RenderJob job(scene, settings, "furnace");
  LocalRenderResult r = renderLocally(job);
  const double D = maxDepth < 0 ? INFINITY : maxDepth;
  const double factor = (1 - std::pow(double(albedo), D)) / (1 - albedo);
  PixelStats st = pixelStats(r.image);
  const double le[3] = {1.0, 0.5, 2.0};
  for (int c = 0; c < 3; ++c) {
    double expected = le[c] * factor;
    double se = st.stdError[c];
    if (isMarkovChain(algorithm)) {
      // The image scales with Z: its relative standard error adds to the pixels' spread.
      double zRel = std::sqrt(r.bootstrap.normalizationRelativeVariance(r.largeSteps));
      se = std::sqrt(se * se + std::pow(expected * zRel, 2));
    }
    EXPECT_NEAR(st.mean[c], expected, 4 * se + 1e-6 * expected)
        << algorithmName(algorithm) << " channel " << c << " maxDepth " << maxDepth;
  }
  EXPECT_EQ(r.rejected.total(), 0);
}

TEST(Furnace, PathTracing) {
  expectFurnace(Algorithm::PathTracing, -1);
  expectFurnace(Algorithm::PathTracing, 3);
}
TEST(Furnace, Bidirectional) {
  expectFurnace(Algorithm::Bidirectional, -1);
  expectFurnace(Algorithm::Bidirectional, 3);
}
TEST(Furnace, Pssmlt) {
  expectFurnace(Algorithm::PSSMLT, -1);
  expectFurnace(Algorithm::PSSMLT, 3);
}
TEST(Furnace, PssmltOverPathTracing) {
  expectFurnace(Algorithm::PSSMLTOverPT, -1);
  expectFurnace(Algorithm::PSSMLTOverPT, 3);
}
TEST(Furnace, Multiplexed) {
  expectFurnace(Algorithm::MMLT, -1);
  expectFurnace(Algorithm::MMLT, 3);
}
TEST(Furnace, PathSpace) {
  expectFurnace(Algorithm::MLT, -1);
  expectFurnace(Algorithm::MLT, 3);
}
// ERPT spreads each seed's energy over many pixels, so the pixels' spread says nothing about the
// image mean's error: sixteen independent renders give it, with Student's t for 15 degrees of
// freedom at the same level as 4 standard errors of a normal (about 6e-5 two-sided: 5.2).
void expectFurnaceEnergyRedistribution(int maxDepth) {
  const float albedo = 0.6f;
  auto scene = std::make_shared<Scene>(whiteFurnace(albedo, maxDepth));
  const int renders = 16;
  std::vector<double> means[3];
  for (int k = 0; k < renders; ++k) {
    RenderSettings settings;
    settings.algorithm = Algorithm::ERPT;
    settings.samplesPerPixel = 8;
    settings.erptLength = 20;
    settings.seed = 100 + k;
    settings.bootstrapSamples = 1 << 14;
    RenderJob job(scene, settings, "furnace");
    LocalRenderResult r = renderLocally(job);
    EXPECT_EQ(r.rejected.total(), 0);
    PixelStats st = pixelStats(r.image);
    for (int c = 0; c < 3; ++c) means[c].push_back(st.mean[c]);
  }
  const double D = maxDepth < 0 ? INFINITY : maxDepth;
  const double factor = (1 - std::pow(double(albedo), D)) / (1 - albedo);
  const double le[3] = {1.0, 0.5, 2.0};
  for (int c = 0; c < 3; ++c) {
    const MeanEstimate e = meanOfIndependent(means[c]);
    EXPECT_NEAR(e.mean, le[c] * factor, 5.2 * e.standardError)
        << "erpt channel " << c << " maxDepth " << maxDepth;
  }
}

TEST(Furnace, EnergyRedistribution) {
  expectFurnaceEnergyRedistribution(-1);
  expectFurnaceEnergyRedistribution(3);
}

// A floor (a large rectangle at y = 0, normal +y) lit by a sphere of radius r at height h, or by
// a point light or a spot aimed straight down at its centre, seen from above by a narrow camera,
// direct light only (maxDepth 2). The point light has the sphere's irradiance far away: I =
// pi Le r^2; the spot (pbrt-v3's falloff) is fully bright to 10 degrees off its axis and dark
// beyond 28, and the camera sees the floor between 13 and 27 degrees.
constexpr float kRho = 0.5f, kHeight = 2.0f, kRadius = 0.25f, kLe = 10.0f;
constexpr double kCosSpotStart = 0.98480775301220802032, kCosSpotTotal = 0.88294759285892694203;
// TwoSidedQuad: a square of side 2 r at height h, facing up (away from the floor) but emitting on
// both sides, whose irradiance is Lambert's formula for a polygon.
enum class FloorLight { Sphere, Point, Spot, TwoSidedQuad };

SceneDescription irradianceScene(FloorLight lightKind = FloorLight::Sphere, float fov = 10) {
  const float rho = kRho, h = kHeight, radius = kRadius, le = kLe;
  SceneDescription d;
  // Camera at (0.6, 3, 0.4) looking straight down: camera +z -> world -y.
  Matrix4 m = Matrix4::identity();
  m.m[0] = {1, 0, 0, 0.6};
  // Below the two-sided quad (at height 2), so that a wide view sees only the floor.
  m.m[1] = {0, 0, -1, lightKind == FloorLight::TwoSidedQuad ? 1.5 : 3.0};
  m.m[2] = {0, 1, 0, 0.4};
  d.camera.toWorld = m;
  d.camera.fovDegrees = fov;
  d.camera.width = 16;
  d.camera.height = 16;
  d.camera.filter = FilterType::Box;
  d.maxDepth = 2;
  BsdfDescription floor;
  floor.reflectance = Spectrum(rho);
  d.bsdfs.push_back(floor);
  BsdfDescription black;
  black.reflectance = Spectrum(0.0f);
  d.bsdfs.push_back(black);
  ShapeDescription plane;
  plane.positions = {{-50, 0, -50}, {50, 0, -50}, {50, 0, 50}, {-50, 0, 50}};
  plane.indices = {0, 2, 1, 0, 3, 2};  // counter-clockwise seen from +y
  plane.bsdf = 0;
  d.shapes.push_back(plane);
  if (lightKind == FloorLight::TwoSidedQuad) {
    ShapeDescription quad;
    quad.positions = {
        {-radius, h, -radius}, {radius, h, -radius}, {radius, h, radius}, {-radius, h, radius}};
    quad.indices = {0, 2, 1, 0, 3, 2};  // counter-clockwise seen from +y: facing up
    quad.bsdf = 1;
    quad.isEmitter = true;
    quad.radiance = Spectrum(le);
    quad.emitsBothSides = true;
    d.shapes.push_back(quad);
    return d;
  }
  if (lightKind != FloorLight::Sphere) {
    PointLightDescription point;
    point.position = Vec3f(0, h, 0);
    point.intensity = Spectrum(kPi * le * radius * radius);
    if (lightKind == FloorLight::Spot) {
      point.spot = true;
      point.direction = Vec3f(0, -1, 0);
      point.cosFalloffStart = float(kCosSpotStart);
      point.cosTotalWidth = float(kCosSpotTotal);
    }
    d.pointLights.push_back(point);
    return d;
  }
  ShapeDescription light;
  light.type = ShapeDescription::Type::Sphere;
  light.center = Vec3f(0, h, 0);
  light.radius = radius;
  light.bsdf = 1;
  light.isEmitter = true;
  light.radiance = Spectrum(le);
  d.shapes.push_back(light);
  return d;
}

// Radiance of the floor seen through film point `film`: rho / pi * E at the floor point, with
// E = pi Le r^2 h / d^3 (= I h / d^3 for the point light; the spot's times its falloff, pbrt-v3's
// ((cos - cos total) / (cos start - cos total))^4 between the two).
double floorRadiance(const Camera& cam, const Vec2f& film, FloorLight lightKind) {
  Ray ray = cam.generateRay(film);
  Vec3f p = ray.o + ray.d * (-ray.o.y / ray.d.y);
  double dist = length(p - Vec3f(0, kHeight, 0));
  if (lightKind == FloorLight::TwoSidedQuad) {
    // Lambert: E = Le / 2 |sum_i angle(a_i, a_i+1) (n . unit(a_i x a_i+1))|, a_i = v_i - p.
    const double r = kRadius;
    const double v[4][3] = {{-r, kHeight, -r}, {r, kHeight, -r}, {r, kHeight, r}, {-r, kHeight, r}};
    double sum = 0;
    for (int i = 0; i < 4; ++i) {
      const double* a0 = v[i];
      const double* a1 = v[(i + 1) % 4];
      const double a[3] = {a0[0] - p.x, a0[1] - p.y, a0[2] - p.z};
      const double b[3] = {a1[0] - p.x, a1[1] - p.y, a1[2] - p.z};
      const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
      const double angle = std::acos((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb));
      const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                           a[0] * b[1] - a[1] * b[0]};
      const double lc = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
      sum += angle * c[1] / lc;  // the floor's normal is +y
    }
    return kRho / kPi * kLe * 0.5 * std::fabs(sum);
  }
  double falloff = 1;
  if (lightKind == FloorLight::Spot) {
    const double cosTheta = kHeight / dist;
    const double t = (cosTheta - kCosSpotTotal) / (kCosSpotStart - kCosSpotTotal);
    falloff = cosTheta >= kCosSpotStart ? 1 : cosTheta <= kCosSpotTotal ? 0 : t * t * t * t;
  }
  return falloff * kRho * kLe * kRadius * kRadius * kHeight / (dist * dist * dist);
}

// The analytic radiance averaged over pixel (x, y) (a box filter), on a g x g grid.
double pixelFootprintRadiance(const Camera& cam, int x, int y, int g, FloorLight lightKind) {
  double sum = 0;
  for (int j = 0; j < g; ++j) {
    for (int i = 0; i < g; ++i)
      sum += floorRadiance(cam, Vec2f(x + (i + 0.5f) / g, y + (j + 0.5f) / g), lightKind);
  }
  return sum / (g * g);
}

// Two independent renders: each pixel's variance is (a - b)^2 / 2, a measure of the noise that
// does not depend on the expected value, so the bound does not grow with the bias it is there to
// catch. The mean of the two renders' average against the analytic radiance averaged over the
// film, within 4 standard errors (and Z's, by which a Markov chain's image scales).
void expectIrradiance(Algorithm algorithm, FloorLight lightKind = FloorLight::Sphere,
                      float fov = 10) {
  auto scene = std::make_shared<Scene>(irradianceScene(lightKind, fov));
  LocalRenderResult r[2];
  for (int k = 0; k < 2; ++k) {
    RenderSettings settings;
    settings.algorithm = algorithm;
    settings.samplesPerPixel = 128;
    settings.mutationsPerPixel = 1024;  // Markov chains' pixels are noisier than samples'
    settings.seed = 5 + uint64_t(k);
    settings.bootstrapSamples = 1 << 20;  // Z within about 0.5% for the Markov chains
    RenderJob job(scene, settings, "irradiance");
    r[k] = renderLocally(job);
  }
  const Camera& cam = scene->camera();
  const int n = cam.width() * cam.height();
  double variance = 0, meanRendered = 0, meanExpected = 0;
  for (int y = 0; y < cam.height(); ++y) {
    for (int x = 0; x < cam.width(); ++x) {
      const double a = r[0].image.at(x, y).y, b = r[1].image.at(x, y).y;
      variance += (a - b) * (a - b) / 4;  // of the two renders' average
      meanRendered += (a + b) / 2;
      meanExpected += pixelFootprintRadiance(cam, x, y, 8, lightKind);
    }
  }
  meanRendered /= n;
  meanExpected /= n;
  double se = std::sqrt(variance) / n;
  if (isMarkovChain(algorithm)) {
    double zRel =
        std::hypot(std::sqrt(r[0].bootstrap.normalizationRelativeVariance(r[0].largeSteps)),
                   std::sqrt(r[1].bootstrap.normalizationRelativeVariance(r[1].largeSteps))) /
        2;
    se = std::sqrt(se * se + std::pow(meanExpected * zRel, 2));
  }
  // The 1e-3 covers the 8 x 8 quadrature of each footprint.
  EXPECT_NEAR(meanRendered, meanExpected, 4 * se + 1e-3 * meanExpected)
      << algorithmName(algorithm) << ": standard error " << se / meanExpected << " relative";
  EXPECT_LT(se, 0.01 * meanExpected) << algorithmName(algorithm) << ": too noisy to tell";
}

TEST(AnalyticIrradiance, PathTracing) {
  expectIrradiance(Algorithm::PathTracing);
}
TEST(AnalyticIrradiance, Bidirectional) {
  expectIrradiance(Algorithm::Bidirectional);
}
TEST(AnalyticIrradiance, Pssmlt) {
  expectIrradiance(Algorithm::PSSMLT);
}
TEST(AnalyticIrradiance, PssmltOverPathTracing) {
  expectIrradiance(Algorithm::PSSMLTOverPT);
}
TEST(AnalyticIrradiance, Multiplexed) {
  expectIrradiance(Algorithm::MMLT);
}
// Point and spot lights: delta positions that only connections reach (no strategy without
// light vertices), with their intensity and the spot's falloff.
TEST(AnalyticIrradiance, PointAndSpotPathTracing) {
  expectIrradiance(Algorithm::PathTracing, FloorLight::Point);
  expectIrradiance(Algorithm::PathTracing, FloorLight::Spot);
}
TEST(AnalyticIrradiance, PointAndSpotBidirectional) {
  expectIrradiance(Algorithm::Bidirectional, FloorLight::Point);
  expectIrradiance(Algorithm::Bidirectional, FloorLight::Spot);
  // Seen through 90 degrees, the floor's paths go to light tracing about as often as to
  // next-event estimation (the camera's density per unit area of floor is no longer far the
  // larger), so that both strategies and their weights are tested.
  expectIrradiance(Algorithm::Bidirectional, FloorLight::Point, 90);
}
TEST(AnalyticIrradiance, PointAndSpotPssmlt) {
  expectIrradiance(Algorithm::PSSMLT, FloorLight::Point);
  expectIrradiance(Algorithm::PSSMLT, FloorLight::Spot);
}
TEST(AnalyticIrradiance, PointAndSpotPssmltOverPathTracing) {
  expectIrradiance(Algorithm::PSSMLTOverPT, FloorLight::Point);
  expectIrradiance(Algorithm::PSSMLTOverPT, FloorLight::Spot);
}
TEST(AnalyticIrradiance, PointAndSpotMultiplexed) {
  expectIrradiance(Algorithm::MMLT, FloorLight::Point);
  expectIrradiance(Algorithm::MMLT, FloorLight::Spot);
}
// A two-sided area light facing away from the floor lights it from its back; seen through 90
// degrees, light tracing from its sides carries much of the weight.
TEST(AnalyticIrradiance, TwoSidedLight) {
  for (Algorithm a : {Algorithm::PathTracing, Algorithm::Bidirectional, Algorithm::PSSMLT,
                      Algorithm::PSSMLTOverPT, Algorithm::MMLT}) {
    expectIrradiance(a, FloorLight::TwoSidedQuad);
    expectIrradiance(a, FloorLight::TwoSidedQuad, 90);
  }
}
TEST(AnalyticIrradiance, PathSpace) {
  expectIrradiance(Algorithm::MLT);
}
// Path-space MLT from point lights (its bidirectional mutation emits from them by their own
// distribution) and from both sides of a two-sided one, through 90 degrees too.
TEST(AnalyticIrradiance, PathSpacePointSpotAndTwoSided) {
  expectIrradiance(Algorithm::MLT, FloorLight::Point);
  expectIrradiance(Algorithm::MLT, FloorLight::Spot);
  expectIrradiance(Algorithm::MLT, FloorLight::Point, 90);
  expectIrradiance(Algorithm::MLT, FloorLight::TwoSidedQuad);
  expectIrradiance(Algorithm::MLT, FloorLight::TwoSidedQuad, 90);
}
// ERPT moves each seed's energy across pixels, so its pixels are not independent estimates; 32
// independent renders are. Per block of 4 x 4 pixels, their mean against the analytic radiance
// averaged over the block, with Student's t for 31 degrees of freedom and a Bonferroni bound over
// the 16 blocks (1e-4 in all): the energy must land where the light falls, block by block.
void expectEnergyRedistributionBlocks(FloorLight lightKind) {
  auto scene = std::make_shared<Scene>(irradianceScene(lightKind, 10));
  const Camera& cam = scene->camera();
  const int renders = 32, blocks = 16, side = cam.width() / 4;
  std::vector<std::vector<double>> blockMeans(blocks);
  for (int k = 0; k < renders; ++k) {
    RenderSettings settings;
    settings.algorithm = Algorithm::ERPT;
    settings.samplesPerPixel = 16;
    settings.erptLength = 20;
    settings.seed = 200 + k;
    settings.bootstrapSamples = 1 << 14;
    RenderJob job(scene, settings, "irradiance");
    LocalRenderResult r = renderLocally(job);
    std::vector<double> sums(blocks, 0.0);
    for (int y = 0; y < cam.height(); ++y) {
      for (int x = 0; x < cam.width(); ++x)
        sums[size_t(x / side + 4 * (y / side))] += r.image.at(x, y).y;
    }
    for (int b = 0; b < blocks; ++b) blockMeans[b].push_back(sums[b] / (side * side));
  }
  const double bound = studentQuantile(renders - 1, 1 - 1e-4 / (2 * blocks));
  for (int b = 0; b < blocks; ++b) {
    double expected = 0;
    for (int y = 0; y < side; ++y) {
      for (int x = 0; x < side; ++x)
        expected +=
            pixelFootprintRadiance(cam, (b % 4) * side + x, (b / 4) * side + y, 8, lightKind);
    }
    expected /= side * side;
    const MeanEstimate e = meanOfIndependent(blockMeans[b]);
    // The 1e-3 covers the 8 x 8 quadrature of each footprint.
    EXPECT_NEAR(e.mean, expected, bound * e.standardError + 1e-3 * expected)
        << "block " << b << ", light " << int(lightKind);
  }
}

TEST(AnalyticIrradiance, EnergyRedistribution) {
  expectEnergyRedistributionBlocks(FloorLight::Sphere);
}
// Seeds from the path tracer's next-event estimation at a point light and at the back of a
// two-sided one, spread by perturbations that keep the light vertex.
TEST(AnalyticIrradiance, EnergyRedistributionPointAndTwoSided) {
  expectEnergyRedistributionBlocks(FloorLight::Point);
  expectEnergyRedistributionBlocks(FloorLight::TwoSidedQuad);
}

}  // namespace
}  // namespace farm

namespace farm {
namespace {

// One BDPT sample's estimate of the image's mean pixel is its splats' total (channel c) over the
// pixel count; n samples with uniform film points give the mean and its standard error.
std::pair<double, double> imageMeanPerSample(const BidirectionalTracer& tracer, const Camera& cam,
                                             Rng* rng, int n, int c) {
  IndependentSampler sampler(rng);
  std::vector<Splat> splats;
  double sum = 0, sumSq = 0;
  for (int k = 0; k < n; ++k) {
    splats.clear();
    tracer.sample(Vec2f(rng->nextFloat() * cam.width(), rng->nextFloat() * cam.height()), sampler,
                  &splats);
    double v = 0;
    for (const Splat& s : splats) v += s.value[c];
    v /= cam.pixelCount();
    sum += v;
    sumSq += v * v;
  }
  double mean = sum / n;
  return {mean, std::sqrt(std::max(0.0, sumSq / n - mean * mean) / n)};
}

// Every MIS heuristic makes BDPT unbiased (the weights of a path's strategies sum to one), so
// each must reproduce the furnace. The spherical furnace is the hard case for the maximum
// heuristic of Veach and Guibas (1994): cosine and area sampling tie exactly everywhere, so a
// rounding-sized disagreement about which strategy wins loses (or doubles) whole paths. The
// bound is 4 standard errors of the per-sample mean; 400k samples make it about 0.02% of the
// answer, well below the 0.13% that an ambiguous winner costs.
TEST(Furnace, BidirectionalWithEveryHeuristic) {
  const float albedo = 0.6f;
  SceneDescription desc = whiteFurnace(albedo, 4);
  Scene scene(desc);
  const double expected = 2.0 * (1 - std::pow(0.6, 4)) / (1 - 0.6);  // blue channel, Le = 2
  for (MisHeuristic h : {MisHeuristic::Balance, MisHeuristic::Power, MisHeuristic::Maximum}) {
    BidirectionalTracer tracer(scene, 4, h);
    Rng rng(17, uint64_t(h));
    auto [mean, se] = imageMeanPerSample(tracer, scene.camera(), &rng, 400000, 2);
    EXPECT_NEAR(mean, expected, 4 * se) << "heuristic " << int(h);
    std::printf("heuristic %d: %+.3g relative, standard error %.3g\n", int(h), mean / expected - 1,
                se / expected);
  }
}

// Direct light from the spherical light onto the floor with each heuristic, the maximum
// heuristic of Veach and Guibas (1994) included: the image mean against the analytic radiance
// averaged over the film.
TEST(AnalyticIrradiance, BidirectionalWithEveryHeuristic) {
  Scene scene(irradianceScene());
  const Camera& cam = scene.camera();
  double expected = 0;
  for (int y = 0; y < cam.height(); ++y) {
    for (int x = 0; x < cam.width(); ++x)
      expected += pixelFootprintRadiance(cam, x, y, 16, FloorLight::Sphere);
  }
  expected /= cam.pixelCount();
  for (MisHeuristic h : {MisHeuristic::Balance, MisHeuristic::Power, MisHeuristic::Maximum}) {
    BidirectionalTracer tracer(scene, 2, h);
    Rng rng(23, uint64_t(h));
    auto [mean, se] = imageMeanPerSample(tracer, cam, &rng, 100000, 1);
    EXPECT_NEAR(mean, expected, 4 * se + 1e-4 * expected) << "heuristic " << int(h);
  }
}

}  // namespace
}  // namespace farm
