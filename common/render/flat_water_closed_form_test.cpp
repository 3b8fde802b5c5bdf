// Specular-diffuse-specular light at every index of refraction (issue 43, part 1), against a
// closed form that needs no renderer: a point light above flat water, a diffuse floor under it,
// the camera above looking down through the surface. Every path that carries light is camera,
// the surface, the floor, the surface, the light (four edges, the scene's maxDepth): the light is
// a point, so no path reaches it by chance, and only path-space MLT's manifold walks (and its
// bootstrap's manifold next-event estimation) find these paths.
//
// The floor's irradiance at distance r from the point under the light, light height h above the
// water, floor depth d below it: the ray leaving the light at angle theta_i to the vertical
// refracts to theta_t (sin theta_t = sin theta_i / n) and meets the floor at
//   rho(theta_i) = h tan theta_i + d tan theta_t,
// so the light's solid angle per floor area is sin theta_i / (rho rho'(theta_i)) (rotational
// symmetry), and E(r) = I T(theta_i) sin theta_i / (rho rho'), T the Fresnel transmittance
// (unpolarised). The floor's radiance in the water is albedo E / pi; the camera sees it through
// the surface scaled by T(theta_c) / n^2 (radiance over n^2 is what crosses an interface
// unchanged). Each pixel's value is that averaged over 8 x 8 points (a box filter).
//
// mlt renders it at indices 1.0001 (nearly no water, a constraint nearly degenerate), 1.1, 1.33,
// 1.5, 2.4 and 4 (a narrow cone of light into the water): each render's image mean against the
// closed form's, within 5 standard errors of the renders' mean (from their spread: the
// bootstrap's Z is shared by every pixel of a render, so the pixels' own spread would understate
// it), and the image's shape (each render over its own mean, against the closed form over its
// mean): the pixels' squared differences over their variance.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/render/local_render.h"
#include "common/render/render_job.h"
#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

constexpr int kSide = 16;
constexpr double kFovDegrees = 40;
constexpr double kIntensity = 10, kAlbedo = 0.8;
constexpr double kLightHeight = 1, kDepth = 1;  // the light above the water, the floor below it
constexpr double kCameraHeight = 2;             // above the water, straight above the light

std::string flatWaterScene(double ior) {
  char xml[2048];
  std::snprintf(xml, sizeof(xml), R"(<?xml version="1.0"?>
<scene version="0.5.0">
  <integrator type="path"><integer name="maxDepth" value="4"/></integrator>
  <sensor type="perspective"><float name="fov" value="%g"/>
    <transform name="toWorld"><lookat origin="0, %g, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="%d"/><integer name="height" value="%d"/>
      <rfilter type="box"/></film>
  </sensor>
  <shape type="rectangle"><transform name="toWorld"><scale x="10" y="10"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="%g, %g, %g"/></bsdf></shape>
  <shape type="rectangle"><transform name="toWorld"><scale x="10" y="10"/><rotate x="1" angle="-90"/><translate y="%g"/></transform>
    <bsdf type="dielectric"><float name="intIOR" value="%.9g"/><float name="extIOR" value="1"/></bsdf></shape>
  <emitter type="point"><point name="position" x="0" y="%g" z="0"/>
    <rgb name="intensity" value="%g, %g, %g"/></emitter>
</scene>
)",
                kFovDegrees, kDepth + kCameraHeight, kSide, kSide, kAlbedo, kAlbedo, kAlbedo,
                kDepth, ior, kDepth + kLightHeight, kIntensity, kIntensity, kIntensity);
  return xml;
}

// Unpolarised Fresnel transmittance at incidence cos theta_i into a medium eta times denser.
double fresnelTransmittance(double cosI, double eta) {
  const double sin2T = (1 - cosI * cosI) / (eta * eta);
  if (sin2T >= 1) return 0;
  const double cosT = std::sqrt(1 - sin2T);
  const double rs = (cosI - eta * cosT) / (cosI + eta * cosT);
  const double rp = (eta * cosI - cosT) / (eta * cosI + cosT);
  return 1 - 0.5 * (rs * rs + rp * rp);
}

// The floor's irradiance at distance r from the point under the light.
double floorIrradiance(double n, double r) {
  auto refracted = [n](double thetaI) { return std::asin(std::sin(thetaI) / n); };
  auto rho = [&](double thetaI) {
    return kLightHeight * std::tan(thetaI) + kDepth * std::tan(refracted(thetaI));
  };
  double lo = 0, hi = M_PI / 2 - 1e-9;  // rho rises with theta_i: bisect for rho = r
  for (int i = 0; i < 100; ++i) (rho(0.5 * (lo + hi)) < r ? lo : hi) = 0.5 * (lo + hi);
  const double thetaI = 0.5 * (lo + hi), thetaT = refracted(thetaI);
  const double rhoPrime =
      kLightHeight / std::pow(std::cos(thetaI), 2) +
      kDepth / std::pow(std::cos(thetaT), 2) * std::cos(thetaI) / (n * std::cos(thetaT));
  // At r = 0, sin theta_i / rho tends to 1 / rho'.
  const double perArea = r < 1e-9 ? 1 / (rhoPrime * rhoPrime) : std::sin(thetaI) / (r * rhoPrime);
  return kIntensity * fresnelTransmittance(std::cos(thetaI), n) * perArea;
}

// The radiance along the camera ray of unit direction d (d.y < 0).
double cameraRadiance(double n, const double d[3]) {
  const double cosC = -d[1], sinC = std::sqrt(std::max(0.0, 1 - cosC * cosC));
  const double sinT = sinC / n, cosT = std::sqrt(1 - sinT * sinT);
  // Where the ray meets the water, then the floor, horizontally from the axis.
  const double atSurface = kCameraHeight * sinC / cosC, below = kDepth * sinT / cosT;
  const double floorRadiance = kAlbedo / M_PI * floorIrradiance(n, atSurface + below);
  return fresnelTransmittance(cosC, n) * floorRadiance / (n * n);
}

// Per pixel, the closed form averaged over 3 x 3 points. The camera looks down -y with +z up
// on the film; the scene is symmetric about the axis, so the film's x sign does not matter.
constexpr int kSub = 8;
std::vector<double> closedForm(double n) {
  const double t = std::tan(0.5 * kFovDegrees * M_PI / 180);
  std::vector<double> out(size_t(kSide) * kSide, 0.0);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      for (int j = 0; j < kSub; ++j) {
        for (int i = 0; i < kSub; ++i) {
          const double sx = (2 * (x + (i + 0.5) / kSub) / kSide - 1) * t;
          const double sz = (1 - 2 * (y + (j + 0.5) / kSub) / kSide) * t;
          const double norm = std::sqrt(sx * sx + sz * sz + 1);
          const double d[3] = {sx / norm, -1 / norm, sz / norm};
          out[size_t(y) * kSide + x] += cameraRadiance(n, d) / (kSub * kSub);
        }
      }
    }
  }
  return out;
}

void expectMltMeetsTheClosedForm(double ior) {
  TempDir dir("flat_water_closed_form_test");
  const std::string file = dir.write("water/scene.xml", flatWaterScene(ior));
  const std::vector<double> reference = closedForm(ior);
  constexpr int kRenders = 6;
  std::vector<std::vector<double>> renders;
  for (int k = 0; k < kRenders; ++k) {
    RenderSettings s;
    s.algorithm = Algorithm::MLT;
    s.mutationsPerPixel = 512;
    s.seed = uint64_t(131 + k);
    s.width = s.height = kSide;
    const LocalRenderResult r = renderLocally(RenderJob(loadScene(file, s), s, "flat-water"));
    EXPECT_EQ(r.rejected.total(), 0);
    std::vector<double> grey(reference.size());
    for (size_t p = 0; p < grey.size(); ++p)
      grey[p] = (double(r.image.rgb[3 * p]) + r.image.rgb[3 * p + 1] + r.image.rgb[3 * p + 2]) / 3;
    renders.push_back(grey);
  }
  // The image means, whose spread gives the standard error of their mean; and the images
  // divided by their own means (each render's Z taken out), whose pixels' spread is their own.
  const size_t n = reference.size();
  double refMean = 0, sum = 0, sum2 = 0, squared = 0, variance = 0;
  for (double v : reference) refMean += v / double(n);
  for (auto& img : renders) {
    double m = 0;
    for (double v : img) m += v / double(n);
    sum += m, sum2 += m * m;
    for (double& v : img) v /= m;
  }
  for (size_t p = 0; p < n; ++p) {
    double m = 0, m2 = 0;
    for (const auto& img : renders) m += img[p], m2 += img[p] * img[p];
    m /= kRenders;
    variance += std::max(0.0, (m2 - kRenders * m * m) / (kRenders - 1)) / kRenders;
    squared += (m - reference[p] / refMean) * (m - reference[p] / refMean);
  }
  const double mean = sum / kRenders;
  const double se = std::sqrt(std::max(0.0, sum2 / kRenders - mean * mean) / (kRenders - 1));
  std::printf(
      "flat water, index %g: mlt's mean %.5f, closed form %.5f (%+.2f%%, se %.2f%%); the "
      "image's shape: squared differences over variance %.2f\n",
      ior, mean, refMean, 100 * (mean / refMean - 1), 100 * se / refMean, squared / variance);
  EXPECT_NEAR(mean, refMean, 5 * se) << "index " << ior;
  EXPECT_LT(squared / variance, 1.5) << "index " << ior;
}

TEST(FlatWaterClosedForm, MltMeetsItAtEveryIndex) {
  for (double ior : {1.0001, 1.1, 1.33, 1.5, 2.4, 4.0}) expectMltMeetsTheClosedForm(ior);
}

}  // namespace
}  // namespace farm
