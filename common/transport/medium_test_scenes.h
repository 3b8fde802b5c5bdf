#pragma once
// Test code only: scenes with participating media whose answers are known in closed form, for
// the tests of path tracing (medium_transport_test) and BDPT (bidirectional_medium_test).
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "common/sampling/rng.h"
#include "common/scene/medium.h"
#include "common/scene/scene_description.h"
#include "common/scene/test_scenes.h"

namespace farm {

// An axis-aligned box as one mesh, its normals outwards, bounding medium `medium`.
inline ShapeDescription mediumBox(const Vec3f& lo, const Vec3f& hi, int medium) {
  const Vec3f e = hi - lo;
  const Vec3f x(e.x, 0, 0), y(0, e.y, 0), z(0, 0, e.z);
  const ShapeDescription faces[6] = {quadShape(lo, y, x, -1),                        // -z
                                     quadShape(Vec3f(lo.x, lo.y, hi.z), x, y, -1),   // +z
                                     quadShape(lo, x, z, -1),                        // -y
                                     quadShape(Vec3f(lo.x, hi.y, lo.z), z, x, -1),   // +y
                                     quadShape(lo, z, y, -1),                        // -x
                                     quadShape(Vec3f(hi.x, lo.y, lo.z), y, z, -1)};  // +x
  ShapeDescription box;
  for (const ShapeDescription& f : faces) {
    const uint32_t base = uint32_t(box.positions.size());
    box.positions.insert(box.positions.end(), f.positions.begin(), f.positions.end());
    for (uint32_t i : f.indices) box.indices.push_back(base + i);
  }
  box.hasMediumInterface = true;
  box.interiorMedium = medium;
  box.nullBoundary = true;
  box.origin = "medium box";
  return box;
}

inline SceneDescription underConstantSky(const Spectrum& Le, int maxDepth) {
  SceneDescription d;
  d.maxDepth = maxDepth;
  d.environment.present = true;
  d.environment.scale = Le;
  return d;
}

inline double exponentialIntegral2(double x) {
  if (x < 1e-12) return 1;
  return std::exp(-x) + x * std::expint(-x);  // E2 = e^-x - x E1, E1(x) = -Ei(-x)
}

// Single scattering of a constant sky Le in the slab 0 <= z <= depth (sigma_t, sigma_s of one
// channel, phase function `phase`), seen along a ray entering its top at cosine mu0 below the
// horizontal: what reaches the eye unscattered plus what the slab scatters once towards it,
//   Le [exp(-st D / mu0) + ss int_0^{D/mu0} exp(-st t) int_S2 p(w) exp(-st l(z, w)) dw dt]
// where l is the way out of the slab from depth z in direction w. Isotropic: the inner integral
// is (E2(st z) + E2(st (D - z))) / 2; otherwise a quadrature over the sphere.
inline double slabSingleScattering(double Le, double st, double ss, double D, double mu0, float g,
                                   bool closedForm) {
  const HenyeyGreenstein phase(g);
  const Vec3f travel(float(std::sqrt(1 - mu0 * mu0)), 0, float(-mu0));  // downwards
  const int nt = closedForm ? 4000 : 200, nmu = 200, nphi = 48;
  const double length = D / mu0, dt = length / nt;
  double scattered = 0;
  for (int i = 0; i < nt; ++i) {
    const double t = (i + 0.5) * dt, z = t * mu0;  // z: depth below the top
    double inner;
    if (closedForm) {
      inner = 0.5 * (exponentialIntegral2(st * z) + exponentialIntegral2(st * (D - z)));
    } else {
      inner = 0;
      for (int a = 0; a < 2 * nmu; ++a) {
        const double mu = -1 + (a + 0.5) / nmu;  // the direction's z
        const double way = mu > 0 ? z / mu : (D - z) / -mu;
        const double s = std::sqrt(1 - mu * mu);
        for (int b = 0; b < nphi; ++b) {
          const double phi = (b + 0.5) * 2 * kPi / nphi;
          const Vec3f w(float(s * std::cos(phi)), float(s * std::sin(phi)), float(mu));
          inner += phase.eval(-travel, w) * std::exp(-st * way) * (1.0 / nmu) * (2 * kPi / nphi);
        }
      }
    }
    scattered += std::exp(-st * t) * inner * dt;
  }
  return Le * (std::exp(-st * length) + ss * scattered);
}

// A scene with its radiance along any ray that enters it from above: radiance(channel, mu0)
// for a ray going down at cosine mu0 from the vertical.
struct SlabScene {
  SceneDescription scene;
  std::function<double(int, double)> radiance;
};

// The slab 0 <= z <= 1, 2000 wide, of coloured extinction and phase function g under a constant
// sky, light scattered at most once (maxDepth 2): slabSingleScattering's answer.
inline SlabScene singleScatteringSlab(float g) {
  const Spectrum Le(1.0f, 0.8f, 1.3f);
  SlabScene slab;
  slab.scene = underConstantSky(Le, 2);  // camera - scattering - sky
  MediumDescription m;
  m.sigmaA = Spectrum(0.3f, 0.1f, 0.0f);
  m.sigmaS = Spectrum(0.5f, 1.0f, 2.0f);
  m.g = g;
  slab.scene.media.push_back(m);
  // 2000 times wider than thick: the infinite slab to within exp(-1000).
  slab.scene.shapes.push_back(mediumBox(Vec3f(-1000, -1000, 0), Vec3f(1000, 1000, 1), 0));
  slab.radiance = [=](int c, double mu0) {
    const double st = double(m.sigmaA[c]) + m.sigmaS[c];
    return slabSingleScattering(Le[c], st, m.sigmaS[c], 1.0, mu0, g, g == 0);
  };
  return slab;
}

// A diffuse floor (albedo rho) at z = 0 under a purely absorbing slab 0.5 <= z <= 1.5 of
// optical thickness tau, lit by a constant sky, light reflected once: the floor's radiance is
// rho Le int 2 mu exp(-tau / mu) dmu = 2 rho Le E3(tau), and a ray down at mu0 sees it times
// exp(-tau / mu0). The slab is bounded by a null boundary, or by an index-matched dielectric
// (Fresnel 0: every ray is refracted straight on, so the answer is the same, but rays cross it
// by sampling its BSDF and no connection passes it: 6 edges from the eye to the sky).
inline SlabScene absorbingSlabOverFloor(bool dielectricBoundary) {
  const Spectrum Le(1.0f, 0.6f, 1.4f);
  SlabScene slab;
  SceneDescription& desc = slab.scene;
  desc = underConstantSky(Le, dielectricBoundary ? 6 : 2);
  MediumDescription m;
  m.sigmaA = Spectrum(0.2f, 0.7f, 1.5f);
  desc.media.push_back(m);
  BsdfDescription floor;
  floor.reflectance = Spectrum(0.8f, 0.5f, 0.3f);
  desc.bsdfs.push_back(floor);
  desc.shapes.push_back(mediumBox(Vec3f(-1000, -1000, 0.5f), Vec3f(1000, 1000, 1.5f), 0));
  if (dielectricBoundary) {
    BsdfDescription matched;
    matched.type = BsdfDescription::Type::Dielectric;
    matched.intIOR = matched.extIOR = 1.0f;
    desc.bsdfs.push_back(matched);
    desc.shapes.back().nullBoundary = false;
    desc.shapes.back().bsdf = 1;
  }
  desc.shapes.push_back(quadShape(Vec3f(-1000, -1000, 0), Vec3f(2000, 0, 0), Vec3f(0, 2000, 0), 0));
  slab.radiance = [=](int c, double mu0) {
    const double tau = double(m.sigmaA[c]);
    const double e3 = 0.5 * (std::exp(-tau) - tau * exponentialIntegral2(tau));
    return std::exp(-tau / mu0) * 2 * floor.reflectance[c] * Le[c] * e3;
  };
  return slab;
}

// Media of albedo 1 under a constant sky Le: nothing is lost, so every ray sees Le, through any
// number of scatterings and whatever bounds the medium: a unit ball of it at the origin bounded
// by a null boundary, the same with the camera inside it, by glass, and a density grid.
struct MediumFurnace {
  std::string name;
  SceneDescription scene;
  Spectrum Le;
};

inline std::vector<MediumFurnace> mediumFurnaces() {
  const Spectrum Le(1.0f, 0.5f, 2.0f);
  std::vector<MediumFurnace> furnaces;
  MediumDescription m;
  m.sigmaS = Spectrum(1.5f, 3.0f, 0.7f);  // optically thick in green: many scatterings
  m.g = 0.5f;
  SceneDescription desc = underConstantSky(Le, -1);
  desc.media.push_back(m);
  ShapeDescription ball = sphereShape(Vec3f(0.0f), 1.0f, -1);
  ball.hasMediumInterface = true;
  ball.interiorMedium = 0;
  ball.nullBoundary = true;
  desc.shapes.push_back(ball);
  furnaces.push_back({"null boundary", desc, Le});

  desc.camera.medium = 0;
  furnaces.push_back({"camera in the medium", desc, Le});
  desc.camera.medium = -1;

  // Glass reflects and refracts without loss.
  BsdfDescription glass;
  glass.type = BsdfDescription::Type::Dielectric;
  glass.intIOR = 1.33f;
  glass.extIOR = 1.0f;
  desc.bsdfs.push_back(glass);
  desc.shapes[0].nullBoundary = false;
  desc.shapes[0].bsdf = 0;
  furnaces.push_back({"glass boundary", desc, Le});

  // A density grid (sigma_t grey), its zeros and ramps inside the ball's box.
  MediumDescription grid;
  grid.type = MediumDescription::Type::Grid;
  grid.sigmaS = Spectrum(4.0f);
  grid.nx = grid.ny = grid.nz = 5;
  Rng rng(2, 2);
  for (int i = 0; i < 125; ++i)
    grid.density.push_back(rng.nextFloat() < 0.2f ? 0 : rng.nextFloat());
  grid.worldToGrid = Matrix4::scale(Vec3f(0.5f)) * Matrix4::translate(Vec3f(1.0f));
  grid.g = -0.3f;
  desc.media[0] = grid;
  desc.shapes[0].nullBoundary = true;
  desc.shapes[0].bsdf = -1;
  furnaces.push_back({"density grid", desc, Le});
  return furnaces;
}

// test_scenes.h's closed white furnace (walls of albedo rho emitting Le inwards, seen from the
// camera at its centre) filled with a medium of albedo 1: a uniform radiance field is in
// equilibrium with such a medium, so the radiance stays Le / (1 - rho) everywhere. The medium
// is bounded by the furnace's own wall (its exterior, the side its inward normals face), or by
// a larger null-boundary sphere around the furnace, so that the walls, and the light, lie in a
// medium that no surface of theirs names.
inline std::vector<MediumFurnace> filledFurnaces() {
  const float rho = 0.5f;
  std::vector<MediumFurnace> furnaces;
  MediumDescription m;
  m.sigmaS = Spectrum(0.8f, 1.6f, 0.4f);
  m.g = 0.3f;
  SceneDescription desc = whiteFurnace(rho, -1);
  const Spectrum expected = desc.shapes[0].radiance / (1 - rho);
  desc.media.push_back(m);
  desc.camera.medium = 0;
  desc.shapes[0].hasMediumInterface = true;
  desc.shapes[0].exteriorMedium = 0;
  furnaces.push_back({"furnace wall bounding the medium", desc, expected});

  desc.shapes[0].hasMediumInterface = false;
  desc.shapes[0].exteriorMedium = -1;
  ShapeDescription around = sphereShape(desc.shapes[0].center, 3.0f, -1);
  around.hasMediumInterface = true;
  around.interiorMedium = 0;
  around.nullBoundary = true;
  desc.shapes.push_back(around);
  furnaces.push_back({"furnace inside a ball of medium", desc, expected});
  return furnaces;
}

}  // namespace farm
