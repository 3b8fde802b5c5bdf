#pragma once
// A pool for the tests of paths through a specular interface (test code only): a flat water
// surface (index 1.33) at y = 1 over a diffuse floor at y = 0, both 20 wide, a point light above
// the water and a camera looking down through it, so that everything the camera sees is the
// floor through the water, lit through it: paths L S D S E, which BDPT cannot build at all (no
// camera path hits a point, no connection joins a specular vertex). With paths of at most four
// edges that is all the image holds, and its optics are written out here in closed form.
#include <algorithm>
#include <cmath>

#include "common/scene/camera.h"
#include "common/scene/scene_description.h"
#include "common/scene/test_scenes.h"

namespace farm {
namespace pool {

inline constexpr double kEta = 1.33, kRho = 0.5, kIntensity = 10,
                        kWater = 1;  // the surface at y = 1
inline const Vec3f kLight(0.2f, 2.5f, -0.1f);

inline SceneDescription scene() {
  SceneDescription d;
  d.camera.toWorld = Matrix4::lookAt(Vec3f(0.6f, 3, 0.4f), Vec3f(0, 0, 0), Vec3f(0, 0, 1));
  d.camera.fovDegrees = 40;
  d.camera.width = d.camera.height = 64;
  d.maxDepth = -1;
  BsdfDescription floor, water;
  floor.reflectance = Spectrum(float(kRho));
  water.type = BsdfDescription::Type::Dielectric;
  water.intIOR = float(kEta), water.extIOR = 1;
  d.bsdfs = {floor, water};
  d.shapes.push_back(quadShape(Vec3f(-10, 0, -10), Vec3f(0, 0, 20), Vec3f(20, 0, 0), 0));
  d.shapes.push_back(
      quadShape(Vec3f(-10, float(kWater), -10), Vec3f(0, 0, 20), Vec3f(20, 0, 0), 1));
  PointLightDescription light;
  light.position = kLight;
  light.intensity = Spectrum(float(kIntensity));
  d.pointLights.push_back(light);
  return d;
}

// --- The optics, in closed form ----------------------------------------------------------------

// Unpolarized Fresnel transmittance of the air-water interface for an angle of incidence in air.
inline double transmittance(double cosAir) {
  const double sinWater = std::sqrt(std::max(0.0, 1 - cosAir * cosAir)) / kEta;
  const double cosWater = std::sqrt(1 - sinWater * sinWater);
  const double rs = (cosAir - kEta * cosWater) / (cosAir + kEta * cosWater);
  const double rp = (kEta * cosAir - cosWater) / (kEta * cosAir + cosWater);
  return 1 - 0.5 * (rs * rs + rp * rp);
}

// Irradiance on the floor at horizontal distance r from below the light: a ray leaving the light
// at angle a from the vertical meets the floor at r(a) = h1 tan a + h2 tan b (sin a = eta sin b),
// so the solid angle per floor area is sin a / (r dr/da), times the intensity and the share the
// surface lets through.
inline double floorIrradiance(double r) {
  const double h1 = double(kLight.y) - kWater, h2 = kWater;
  auto reach = [&](double a) {
    const double b = std::asin(std::sin(a) / kEta);
    return h1 * std::tan(a) + h2 * std::tan(b);
  };
  double lo = 0, hi = 0.5 * M_PI - 1e-9;
  for (int i = 0; i < 200; ++i) (reach(0.5 * (lo + hi)) < r ? lo : hi) = 0.5 * (lo + hi);
  const double a = 0.5 * (lo + hi), b = std::asin(std::sin(a) / kEta);
  const double drda = h1 / (std::cos(a) * std::cos(a)) +
                      h2 / (std::cos(b) * std::cos(b)) * std::cos(a) / (kEta * std::cos(b));
  return kIntensity * transmittance(std::cos(a)) * std::sin(a) / (r * drda);
}

// The radiance the camera receives through film point `film` from the floor lit through the
// water: the floor's radiance rho / pi E, through the surface back into air (the Fresnel share,
// and radiance divided by eta^2 as the beam widens).
inline double filmRadiance(const Camera& camera, const Vec2f& film) {
  const Ray ray = camera.generateRay(film);
  const double ox = ray.o.x, oy = ray.o.y, oz = ray.o.z;
  double dx = ray.d.x, dy = ray.d.y, dz = ray.d.z;
  const double dl = std::sqrt(dx * dx + dy * dy + dz * dz);
  dx /= dl, dy /= dl, dz /= dl;
  const double t = (kWater - oy) / dy;
  const double sx = ox + t * dx, sz = oz + t * dz;
  const double cosAir = -dy, sinAir = std::sqrt(1 - cosAir * cosAir);
  const double sinWater = sinAir / kEta, cosWater = std::sqrt(1 - sinWater * sinWater);
  // Horizontally the ray keeps its heading; it descends kWater at cosWater.
  const double horizontal = std::sqrt(dx * dx + dz * dz);
  const double run = kWater * sinWater / cosWater;
  const double fx = sx + (horizontal > 0 ? dx / horizontal * run : 0);
  const double fz = sz + (horizontal > 0 ? dz / horizontal * run : 0);
  const double r = std::hypot(fx - kLight.x, fz - kLight.z);
  return transmittance(cosAir) / (kEta * kEta) * kRho / M_PI * floorIrradiance(r);
}

// The image's integral over the whole film (pixels), by a midpoint rule of n x n points a pixel.
inline double filmIntegral(const Camera& camera, int n = 4) {
  double sum = 0;
  for (int y = 0; y < camera.height() * n; ++y)
    for (int x = 0; x < camera.width() * n; ++x)
      sum += filmRadiance(camera, Vec2f((x + 0.5f) / n, (y + 0.5f) / n));
  return sum / (n * n);
}

}  // namespace pool
}  // namespace farm
