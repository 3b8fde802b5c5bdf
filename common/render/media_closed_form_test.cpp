// Participating media against closed forms that need no renderer (issue 43): what path tracing
// and BDPT render through a homogeneous medium is held to integrals this file evaluates with its
// own geometry, transmittance and phase function, none of the renderer's.
//
// - Single scattering from a point light (intensity I) in an infinite homogeneous medium, seen
//   along a camera ray x(t) = t d from the origin: with maxDepth 2 (camera, a medium vertex, the
//   light) each channel's radiance is the 1-D integral
//     L(d) = int_0^inf sigma_s e^{-sigma_t t} p(cos) I e^{-sigma_t r} / r^2 dt,
//   r = |q - x(t)| to the light at q, p Henyey and Greenstein's phase function of the cosine
//   between the light's direction before (x - q) / r and after (-d) the scattering.
// - A slab of absorbing medium (thickness D, no scattering) before an emitting wall of
//   radiance Le, seen directly (maxDepth 1): L(d) = Le e^{-sigma_a D / cos theta}.
// - A ball of a medium of albedo one around a point light, seen from afar, paths of any length:
//   all of the light's power leaves the ball, so the irradiance at the pinhole is the light's
//   intensity over the distance squared (of which the image holds the scattered part).
//
// Each pixel of the reference is the closed form averaged over the pixel's square of the film
// (a box filter) by the midpoint rule. The renders' errors are measured against it from their
// own spread: K renders of independent seeds give each pixel's mean and the variance of that
// mean, and over the image the squared differences from the closed form add up to that
// variance (ratio about 1) with the image's mean, and each channel's, within 4 standard
// errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/render/local_render.h"
#include "common/render/render_job.h"
#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

constexpr int kSide = 16;           // the film, kSide x kSide pixels
constexpr double kFovDegrees = 40;  // horizontal and, the film square, vertical
constexpr int kRenders = 4;         // independent seeds per algorithm

struct Rgb {
  double c[3] = {0, 0, 0};
};

// The pinhole's ray through film point (fx, fy) (pixels, y down) of a camera at the origin
// looking along +z with +y up; the sign of x does not matter to these scenes, symmetric in x.
void filmRay(double fx, double fy, double d[3]) {
  const double t = std::tan(0.5 * kFovDegrees * M_PI / 180);
  const double sx = (2 * fx / kSide - 1) * t, sy = (1 - 2 * fy / kSide) * t;
  const double n = std::sqrt(sx * sx + sy * sy + 1);
  d[0] = sx / n, d[1] = sy / n, d[2] = 1 / n;
}

// The closed form averaged over each pixel by the midpoint rule on subpixels x subpixels points:
// reference[(y * kSide + x) * 3 + channel].
template <typename Radiance>
std::vector<double> pixelAverages(const Radiance& radiance, int subpixels) {
  std::vector<double> out(size_t(kSide) * kSide * 3, 0.0);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      Rgb sum;
      for (int j = 0; j < subpixels; ++j) {
        for (int i = 0; i < subpixels; ++i) {
          double d[3];
          filmRay(x + (i + 0.5) / subpixels, y + (j + 0.5) / subpixels, d);
          const Rgb l = radiance(d);
          for (int c = 0; c < 3; ++c) sum.c[c] += l.c[c];
        }
      }
      for (int c = 0; c < 3; ++c)
        out[(size_t(y) * kSide + x) * 3 + c] = sum.c[c] / (subpixels * subpixels);
    }
  }
  return out;
}

struct Fit {
  double mean = 0, reference = 0, se = 0, ratio = 0;
  // Per channel: a renderer that samples distances by the channels' mixture keeps their sum
  // and can shift their balance.
  double channelMean[3] = {0, 0, 0}, channelReference[3] = {0, 0, 0}, channelSe[3] = {0, 0, 0};
};

// K renders against the reference: the image means and the squared differences over their
// variance (each pixel's mean's, from the renders' spread, and no less than a float image's
// rounding, 1e-5 of the value: where the closed form is nearly flat over a pixel and the
// medium's estimate exact, as through the slab's middle, the spread is that small).
Fit fit(const std::vector<Image>& renders, const std::vector<double>& reference) {
  const size_t n = reference.size();
  const double k = double(renders.size());
  double sum = 0, refSum = 0, var = 0, squared = 0;
  Fit f;
  for (size_t i = 0; i < n; ++i) {
    double m = 0, m2 = 0;
    for (const Image& img : renders) m += img.rgb[i], m2 += double(img.rgb[i]) * img.rgb[i];
    m /= k;
    const double v = std::max(std::max(0.0, (m2 - k * m * m) / (k - 1)) / k, 1e-10 * m * m);
    sum += m, refSum += reference[i];
    var += v;
    squared += (m - reference[i]) * (m - reference[i]);
    f.channelMean[i % 3] += m / double(n / 3);
    f.channelReference[i % 3] += reference[i] / double(n / 3);
    f.channelSe[i % 3] += v / (double(n / 3) * double(n / 3));
  }
  for (double& se : f.channelSe) se = std::sqrt(se);
  f.mean = sum / double(n);
  f.reference = refSum / double(n);
  f.se = std::sqrt(var) / double(n);
  f.ratio = squared / var;
  return f;
}

std::vector<Image> render(const std::string& file, Algorithm algorithm, int spp,
                          int renders = kRenders) {
  std::vector<Image> out;
  for (int k = 0; k < renders; ++k) {
    RenderSettings s;
    s.algorithm = algorithm;
    s.samplesPerPixel = spp;
    s.seed = uint64_t(101 + k);
    s.width = kSide;
    s.height = kSide;
    RenderJob job(loadScene(file, s), s, "media-closed-form");
    out.push_back(renderLocally(job).image);
  }
  return out;
}

void expectFits(const char* what, Algorithm algorithm, const std::vector<Image>& renders,
                const std::vector<double>& reference) {
  const Fit f = fit(renders, reference);
  std::printf(
      "%s, %s: mean %.5f, closed form %.5f (se %.5f), squared differences over "
      "variance %.3f\n",
      what, algorithmName(algorithm), f.mean, f.reference, f.se, f.ratio);
  EXPECT_GT(f.reference, 0.0);
  EXPECT_NEAR(f.mean, f.reference, 4 * f.se) << what << ", " << algorithmName(algorithm);
  EXPECT_LT(f.ratio, 1.3) << what << ", " << algorithmName(algorithm);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(f.channelMean[c], f.channelReference[c], 4 * f.channelSe[c])
        << what << ", " << algorithmName(algorithm) << ", channel " << c;
  }
}

// The camera the scenes share: at (0, 0, z), looking down +z, kSide pixels square; `inside` is
// more of its XML (the medium it sits in).
std::string sensor(const std::string& inside = "", double fovDegrees = kFovDegrees, double z = 0) {
  char xml[1024];
  std::snprintf(xml, sizeof(xml), R"(  <sensor type="perspective"><float name="fov" value="%g"/>
    <transform name="toWorld"><lookat origin="0, 0, %g" target="0, 0, %g" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="%d"/><integer name="height" value="%d"/>
      <rfilter type="box"/></film>
%s  </sensor>
)",
                fovDegrees, z, z + 1, kSide, kSide, inside.c_str());
  return xml;
}

// ---- Single scattering from a point light ----

// A homogeneous medium around the camera and a point light: inside a cube of null boundaries
// (boxHalf, half its side) or, with boxHalf 0, filling all space.
struct PointInFog {
  double sigmaS[3], sigmaA[3], g;
  double light[3];
  double intensity;
  double boxHalf;
};

// The channels differ (the renderer samples distances by their mixture) and the phase function
// leans forward. The light is outside the field of view (34 degrees above the axis, the film
// reaching 20): along the light's own direction the radiance has an integrable singularity (as
// 1 / angle) that a pixel's midpoint rule would not average. A box of half a side 40 leaves
// e^{-sigma_t 40} <= e^{-20} beyond it.
constexpr PointInFog kBoxedFog = {{0.4, 0.25, 0.1}, {0.1, 0.2, 0.3}, 0.4, {0.0, 1.6, 2.4}, 10, 40};
// A thin medium that fills all space, the light behind the camera: a camera ray scatters 30
// units away on average, and 22% of the light comes from beyond twice the scene's reach (the
// light's distance), where a path survives only by the roulette of Scene::survivalBeyondReach.
// Rendered with the roulette's 1/q left out, pt and bdpt came out 14% dark (4 renders: 80
// standard errors).
constexpr PointInFog kBoundlessFog = {
    {0.02, 0.015, 0.01}, {0.01, 0.01, 0.02}, 0.0, {0.0, 0.6, -1.5}, 10, 0};

// A scene of one homogeneous medium "fog" and a point light: `shapes` holds the sensor and
// the shapes, in Mitsuba's XML.
std::string fogScene(int maxDepth, const double sigmaA[3], const double sigmaS[3], double g,
                     const std::string& shapes, const double light[3], double intensity) {
  char xml[4096];
  std::snprintf(xml, sizeof(xml), R"(<?xml version="1.0"?>
<scene version="0.5.0">
  <integrator type="path"><integer name="maxDepth" value="%d"/></integrator>
  <medium type="homogeneous" id="fog">
    <rgb name="sigmaA" value="%g, %g, %g"/><rgb name="sigmaS" value="%g, %g, %g"/>
    <phase type="hg"><float name="g" value="%g"/></phase>
  </medium>
%s  <emitter type="point"><point name="position" x="%g" y="%g" z="%g"/>
    <rgb name="intensity" value="%g, %g, %g"/></emitter>
</scene>
)",
                maxDepth, sigmaA[0], sigmaA[1], sigmaA[2], sigmaS[0], sigmaS[1], sigmaS[2], g,
                shapes.c_str(), light[0], light[1], light[2], intensity, intensity, intensity);
  return xml;
}

std::string singleScatteringScene(const PointInFog& f) {
  char box[512] = "";
  if (f.boxHalf > 0) {
    std::snprintf(
        box, sizeof(box),
        R"(  <shape type="cube"><transform name="toWorld"><scale x="%g" y="%g" z="%g"/></transform>
    <ref name="interior" id="fog"/></shape>
)",
        f.boxHalf, f.boxHalf, f.boxHalf);
  }
  return fogScene(2, f.sigmaA, f.sigmaS, f.g, sensor("    <ref id=\"fog\"/>\n") + box, f.light,
                  f.intensity);
}

double henyeyGreenstein(double g, double cosTheta) {
  return (1 - g * g) / (4 * M_PI * std::pow(1 + g * g - 2 * g * cosTheta, 1.5));
}

// The integrand at distance t along the ray, added to *sum with weight w.
void addSingleScattered(const PointInFog& f, const double d[3], double t, double w, Rgb* sum) {
  const double x[3] = {t * d[0], t * d[1], t * d[2]};
  const double v[3] = {x[0] - f.light[0], x[1] - f.light[1], x[2] - f.light[2]};
  const double r = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const double cosTheta = -(v[0] * d[0] + v[1] * d[1] + v[2] * d[2]) / r;
  const double common = henyeyGreenstein(f.g, cosTheta) * f.intensity / (r * r);
  for (int c = 0; c < 3; ++c) {
    const double sigmaT = f.sigmaS[c] + f.sigmaA[c];
    sum->c[c] += w * f.sigmaS[c] * std::exp(-sigmaT * (t + r)) * common;
  }
}

// The integral along the ray by Simpson's rule: in the box, steps of 0.01 out to its half side
// (the peak, where the ray passes the light, is about 1 wide); in a medium without end, over
// s in [0, 1) with t = s / (1 - s) (dt = ds / (1 - s)^2; the integrand falls as e^{-2 sigma_t t}
// / t^2, to 0 at s = 1), steps of 1e-5 in s (at most 0.04 in t by t = 60).
Rgb singleScattered(const PointInFog& f, const double d[3]) {
  Rgb sum;
  if (f.boxHalf > 0) {
    constexpr int kSteps = 4000;
    const double h = f.boxHalf / kSteps;
    for (int i = 0; i <= kSteps; ++i)
      addSingleScattered(f, d, i * h, (i == 0 || i == kSteps) ? 1 : (i % 2 ? 4 : 2), &sum);
    for (double& c : sum.c) c *= h / 3;
    return sum;
  }
  constexpr int kSteps = 100000;
  const double h = 1.0 / kSteps;
  for (int i = 0; i < kSteps; ++i) {
    const double s = i * h, jacobian = 1 / ((1 - s) * (1 - s));
    addSingleScattered(f, d, s / (1 - s), (i == 0 ? 1 : (i % 2 ? 4 : 2)) * jacobian, &sum);
  }
  for (double& c : sum.c) c *= h / 3;
  return sum;
}

// pt and bdpt, each from kRenders seeds, against the closed form averaged over subpixels^2
// points a pixel.
void expectSingleScatteringFits(const char* what, const PointInFog& fog, int subpixels) {
  TempDir dir("media_closed_form_test");
  const std::string file = dir.write("single/scene.xml", singleScatteringScene(fog));
  const std::vector<double> reference =
      pixelAverages([&](const double d[3]) { return singleScattered(fog, d); }, subpixels);
  expectFits(what, Algorithm::PathTracing, render(file, Algorithm::PathTracing, 1024), reference);
  expectFits(what, Algorithm::Bidirectional, render(file, Algorithm::Bidirectional, 512),
             reference);
}

TEST(MediaClosedForm, SingleScatteringFromAPointLight) {
  expectSingleScatteringFits("single scattering", kBoxedFog, 4);
}

TEST(MediaClosedForm, SingleScatteringFromBeyondTheScenesReach) {
  expectSingleScatteringFits("boundless single scattering", kBoundlessFog, 2);
}

// ---- An absorbing slab before an emitting wall ----

constexpr double kSlabAbsorption[3] = {0.3, 0.8, 1.6};
constexpr double kSlabFront = 1, kSlabBack = 2;  // z
constexpr double kWall = 3;                      // z
constexpr double kWallRadiance = 2;

std::string slabScene() {
  char xml[2048];
  std::snprintf(xml, sizeof(xml), R"(<?xml version="1.0"?>
<scene version="0.5.0">
  <integrator type="path"><integer name="maxDepth" value="1"/></integrator>
  <medium type="homogeneous" id="slab">
    <rgb name="sigmaA" value="%g, %g, %g"/><rgb name="sigmaS" value="0, 0, 0"/>
  </medium>
%s  <shape type="cube">
    <transform name="toWorld"><scale x="20" y="20" z="%g"/><translate x="0" y="0" z="%g"/></transform>
    <ref name="interior" id="slab"/></shape>
  <shape type="rectangle">
    <transform name="toWorld"><scale x="20" y="20"/><rotate y="1" angle="180"/><translate x="0" y="0" z="%g"/></transform>
    <emitter type="area"><rgb name="radiance" value="%g, %g, %g"/></emitter></shape>
</scene>
)",
                kSlabAbsorption[0], kSlabAbsorption[1], kSlabAbsorption[2], sensor().c_str(),
                0.5 * (kSlabBack - kSlabFront), 0.5 * (kSlabBack + kSlabFront), kWall,
                kWallRadiance, kWallRadiance, kWallRadiance);
  return xml;
}

Rgb throughTheSlab(const double d[3]) {
  Rgb l;
  for (int c = 0; c < 3; ++c)
    l.c[c] = kWallRadiance * std::exp(-kSlabAbsorption[c] * (kSlabBack - kSlabFront) / d[2]);
  return l;
}

TEST(MediaClosedForm, AnAbsorbingSlabBeforeAnEmittingWall) {
  TempDir dir("media_closed_form_test");
  const std::string file = dir.write("slab/scene.xml", slabScene());
  const std::vector<double> reference = pixelAverages(throughTheSlab, 16);
  expectFits("absorbing slab", Algorithm::PathTracing, render(file, Algorithm::PathTracing, 64),
             reference);
  expectFits("absorbing slab", Algorithm::Bidirectional, render(file, Algorithm::Bidirectional, 64),
             reference);
}

// ---- A ball of albedo one around a point light: all of its power leaves ----

// A ball of radius R of a medium that scatters and does not absorb, a point light of intensity
// I at its centre, in vacuum, seen from distance D. Every photon leaves the ball in the end, and
// the light field outside is symmetric about the centre, so the net flux through the sphere of
// radius D is the light's power 4 pi I, spread evenly: the irradiance at the pinhole, facing the
// centre, is I / D^2. Of it the unscattered part, I e^{-sigma_t R} / D^2, comes from the centre
// itself, a point no camera ray finds (pt never meets the light, bdpt's light tracing leaves
// point lights out); the image holds the rest, I (1 - e^{-sigma_t R}) / D^2 in each channel,
// whatever the phase function and however many times the light scatters. On the film, at
// distance 1, the irradiance is the sum over pixels of their radiance times their area times
// cos^4 of the angle off the axis (cos for the pinhole's, cos^3 for the solid angle of an area
// of the film). With a bubble of vacuum of radius b about the light (null boundaries both), the
// light goes through vacuum first and e^{-sigma_t (R - b)} of it leaves unscattered; without,
// the light sits in the medium and its own subpaths start there. Path tracing meets the
// light only by next-event estimation, whose I / r^2 from a medium vertex at distance r has
// infinite variance when vertices come arbitrarily close (their density near it falls only as
// r^2): it renders the ball with the bubble only.
constexpr double kBallSigmaS[3] = {3.0, 1.5, 0.6};  // 5%, 22%, 55% unscattered
constexpr double kBallG = 0.6;
constexpr double kBallRadius = 1, kBallDistance = 8, kBallIntensity = 10;
constexpr double kBallFovDegrees = 16;  // the ball's edge 7.2 degrees off the axis

// A sphere about the origin that holds the fog inside (interior) or outside (exterior).
std::string fogSphere(double radius, const char* side) {
  char xml[512];
  std::snprintf(
      xml, sizeof(xml),
      R"(  <shape type="sphere"><point name="center" x="0" y="0" z="0"/><float name="radius" value="%g"/>
    <ref name="%s" id="fog"/></shape>
)",
      radius, side);
  return xml;
}

std::string albedoOneBallScene(double bubble) {
  std::string shapes =
      sensor("", kBallFovDegrees, -kBallDistance) + fogSphere(kBallRadius, "interior");
  if (bubble > 0) shapes += fogSphere(bubble, "exterior");
  constexpr double kNoAbsorption[3] = {0, 0, 0}, kCentre[3] = {0, 0, 0};
  return fogScene(-1, kNoAbsorption, kBallSigmaS, kBallG, shapes, kCentre, kBallIntensity);
}

// Each render's irradiance at the pinhole per channel against the closed form, within 4.5
// standard errors of the renders' mean (from their spread: 8 renders, 7 degrees of freedom, so
// that t beyond 4.5 has a chance of 0.3%).
void expectTheBallsPowerLeaves(Algorithm algorithm, int spp, double bubble) {
  TempDir dir("media_closed_form_test");
  const std::string file = dir.write("ball/scene.xml", albedoOneBallScene(bubble));
  // Each pixel's area times its mean cos^4 (midpoint rule, 8 x 8 points).
  const double half = std::tan(0.5 * kBallFovDegrees * M_PI / 180), side = 2 * half / kSide;
  std::vector<double> weight(size_t(kSide) * kSide, 0.0);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      for (int j = 0; j < 8; ++j) {
        for (int i = 0; i < 8; ++i) {
          const double u = -half + (x + (i + 0.5) / 8) * side,
                       v = -half + (y + (j + 0.5) / 8) * side;
          const double cos2 = 1 / (1 + u * u + v * v);
          weight[size_t(y) * kSide + x] += cos2 * cos2 * side * side / 64;
        }
      }
    }
  }
  constexpr int kBallRenders = 8;
  const std::vector<Image> renders = render(file, algorithm, spp, kBallRenders);
  for (int c = 0; c < 3; ++c) {
    double sum = 0, sum2 = 0;
    for (const Image& img : renders) {
      double e = 0;
      for (size_t p = 0; p < weight.size(); ++p) e += weight[p] * img.rgb[3 * p + size_t(c)];
      sum += e, sum2 += e * e;
    }
    const double mean = sum / kBallRenders;
    const double se =
        std::sqrt(std::max(0.0, sum2 / kBallRenders - mean * mean) / (kBallRenders - 1));
    const double expected = kBallIntensity *
                            (1 - std::exp(-kBallSigmaS[c] * (kBallRadius - bubble))) /
                            (kBallDistance * kBallDistance);
    std::printf(
        "albedo-one ball, bubble %g, %s, channel %d: irradiance %.6f, closed form %.6f (se "
        "%.6f)\n",
        bubble, algorithmName(algorithm), c, mean, expected, se);
    EXPECT_NEAR(mean, expected, 4.5 * se)
        << algorithmName(algorithm) << ", bubble " << bubble << ", channel " << c;
  }
}

TEST(MediaClosedForm, AnAlbedoOneBallLetsAllOfItsLightsPowerOut) {
  expectTheBallsPowerLeaves(Algorithm::Bidirectional, 512, 0);
  expectTheBallsPowerLeaves(Algorithm::PathTracing, 2048, 0.1);
  expectTheBallsPowerLeaves(Algorithm::Bidirectional, 512, 0.1);
}

}  // namespace
}  // namespace farm
