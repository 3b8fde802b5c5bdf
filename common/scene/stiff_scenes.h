#pragma once
// The stiff and extreme scenes of the stability suite (test code only), each with a known
// answer or an exact equivalence:
//  - furnace boxes: a closed box whose every face emits Le towards the inside and reflects
//    diffusely with albedo rho has radiance Le (1 - rho^D) / (1 - rho) everywhere for paths of
//    at most D edges, whatever its shape, size, tessellation or the angle it is seen at, and
//    whatever lossless glass stands inside it (radiance is n^2-scaled inside the glass and
//    unscaled again on the way out);
//  - a floor under a spherical light, seen and lit at grazing angles: the floor's radiance is
//    rho Le r^2 h / d^3 (a sphere entirely above the horizon irradiates as a point);
//  - rooms lit by a sphere, which irradiates as a point of the same power whatever its radius,
//    so that a tiny bright sphere gives the image of a large dim one.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "common/scene/scene_description.h"

namespace farm {
namespace stiff {

// A quad a b c d (in order around it) appended to a mesh as two triangles facing `towards`
// (a point on the side the normal must face).
inline void addQuad(ShapeDescription* s, const Vec3f& a, const Vec3f& b, const Vec3f& c,
                    const Vec3f& d, const Vec3f& towards) {
  const uint32_t base = uint32_t(s->positions.size());
  s->positions.insert(s->positions.end(), {a, b, c, d});
  const bool flip = dot(cross(b - a, c - a), towards - a) < 0;
  const uint32_t q[6] = {0, 1, 2, 0, 2, 3};
  for (int k = 0; k < 6; k += 3) {
    s->indices.push_back(base + q[k]);
    s->indices.push_back(base + (flip ? q[k + 2] : q[k + 1]));
    s->indices.push_back(base + (flip ? q[k + 1] : q[k + 2]));
  }
}

// A sphere as a coarse mesh of `stacks` x `slices` faces (triangles at the poles), facing
// outwards, whose vertex normals are the sphere's: the shading normal, interpolated across each
// flat face, parts from the geometric one by up to about pi / stacks, as on any smooth-shaded
// mesh, and most where the faces are largest.
inline ShapeDescription smoothSphere(const Vec3f& center, float radius, int stacks, int slices) {
  ShapeDescription s;
  auto at = [&](int i, int j) {  // stack line i in 0..stacks, slice line j
    const float theta = kPi * float(i) / float(stacks), phi = 2 * kPi * float(j) / float(slices);
    return Vec3f(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
  };
  auto vertex = [&](const Vec3f& unit) {
    s.positions.push_back(center + unit * radius);
    s.normals.push_back(unit);
    return uint32_t(s.positions.size() - 1);
  };
  // Outwards: (b - a) x (c - a) along the unit vector of a face's centre.
  auto triangle = [&](uint32_t a, uint32_t b, uint32_t c) {
    const Vec3f n = cross(s.positions[b] - s.positions[a], s.positions[c] - s.positions[a]);
    const bool flip = dot(n, s.positions[a] + s.positions[b] + s.positions[c] - center * 3) < 0;
    s.indices.insert(s.indices.end(), {a, flip ? c : b, flip ? b : c});
  };
  std::vector<uint32_t> grid;  // (stacks + 1) x slices vertices; the poles repeated
  for (int i = 0; i <= stacks; ++i)
    for (int j = 0; j < slices; ++j) grid.push_back(vertex(at(i, j)));
  auto g = [&](int i, int j) { return grid[size_t(i * slices + (j % slices))]; };
  for (int i = 0; i < stacks; ++i) {
    for (int j = 0; j < slices; ++j) {
      if (i > 0) triangle(g(i, j), g(i, j + 1), g(i + 1, j));
      if (i + 1 < stacks) triangle(g(i, j + 1), g(i + 1, j + 1), g(i + 1, j));
    }
  }
  return s;
}

// The six faces of the box [lo, hi], facing inwards (or outwards), as one mesh.
inline ShapeDescription box(const Vec3f& lo, const Vec3f& hi, bool outward = false) {
  ShapeDescription s;
  auto corner = [&](int i) {
    return Vec3f(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
  };
  const Vec3f centre = (lo + hi) * 0.5f;
  const int faces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                           {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  for (const auto& f : faces) {
    const Vec3f a = corner(f[0]);
    // Towards the centre, or towards the point mirrored through the face.
    const Vec3f towards = outward ? a * 2.0f - centre : centre;
    addQuad(&s, a, corner(f[1]), corner(f[2]), corner(f[3]), towards);
  }
  return s;
}

inline const Spectrum kFurnaceLe(1.0f, 0.5f, 2.0f);
constexpr float kFurnaceAlbedo = 0.5f;

// Le (1 - rho^D) / (1 - rho), D the longest path in edges (-1: unbounded).
inline Spectrum furnaceRadiance(const Spectrum& le, float rho, int maxDepth) {
  const double D = maxDepth < 0 ? INFINITY : maxDepth;
  const float factor = float((1 - std::pow(double(rho), D)) / (1 - rho));
  return le * factor;
}

inline BsdfDescription diffuse(float albedo, bool twoSided = true) {
  BsdfDescription b;
  b.reflectance = Spectrum(albedo);
  b.twoSided = twoSided;
  return b;
}

// Smooth glass of index `ior` in air.
inline BsdfDescription glass(float ior) {
  BsdfDescription b;
  b.type = BsdfDescription::Type::Dielectric;
  b.intIOR = ior;
  b.extIOR = 1;
  return b;
}

inline void makeFurnace(ShapeDescription* s, int bsdf, const Spectrum& le) {
  s->bsdf = bsdf;
  s->isEmitter = true;
  s->radiance = le;
}

// A furnace box [-1, 1]^3 scaled by `scale`, seen from inside at an angle to its faces.
inline SceneDescription furnaceBox(float scale, int maxDepth, const Spectrum& le = kFurnaceLe,
                                   int size = 16) {
  SceneDescription d;
  d.camera.toWorld = Matrix4::lookAt(Vec3f(0.3f, -0.2f, -0.5f) * scale,
                                     Vec3f(0.9f, 0.4f, 1.0f) * scale, Vec3f(0, 1, 0));
  d.camera.fovDegrees = 70;
  d.camera.width = d.camera.height = size;
  d.maxDepth = maxDepth;
  d.bsdfs.push_back(diffuse(kFurnaceAlbedo));
  ShapeDescription walls = box(Vec3f(-scale), Vec3f(scale));
  makeFurnace(&walls, 0, le);
  d.shapes.push_back(walls);
  return d;
}

// A furnace 2 x 2 x `thickness`, the camera in its mid-plane looking along it: the top and the
// bottom are seen at grazing angles, and light reaches them at grazing angles.
inline SceneDescription flatFurnace(float thickness, int maxDepth, int size = 16) {
  SceneDescription d;
  d.camera.toWorld =
      Matrix4::lookAt(Vec3f(-0.9f, 0, 0.1f), Vec3f(1, 0.0002f, 0.3f), Vec3f(0, 1, 0));
  d.camera.fovDegrees = 60;
  d.camera.width = d.camera.height = size;
  d.maxDepth = maxDepth;
  d.bsdfs.push_back(diffuse(kFurnaceAlbedo));
  const float h = thickness / 2;
  ShapeDescription walls = box(Vec3f(-1, -h, -1), Vec3f(1, h, 1));
  makeFurnace(&walls, 0, kFurnaceLe);
  d.shapes.push_back(walls);
  return d;
}

// The furnace box [-1, 1]^3 with each face cut into `strips` emitting shapes of geometrically
// growing widths (ratio 4), each strip into `cells` cells of geometrically growing lengths
// (ratio from 1 to 1e6), two triangles each: 12 strips x cells triangles of areas spanning
// about ten decades, in lights whose powers span four.
inline SceneDescription tessellatedFurnace(int strips, int cells, int maxDepth, int size = 16) {
  SceneDescription d = furnaceBox(1, maxDepth, kFurnaceLe, size);
  d.shapes.clear();
  auto geometricCuts = [](int n, double ratio) {  // 0 = t_0 < ... < t_n = 1
    std::vector<double> t(n + 1, 0.0);
    const double q = std::pow(ratio, 1.0 / std::max(1, n - 1));
    double w = 1, sum = 0;
    for (int i = 0; i < n; ++i) sum += w, w *= q;
    w = 1 / sum;
    for (int i = 0; i < n; ++i) t[i + 1] = t[i] + w, w *= q;
    t[n] = 1;
    return t;
  };
  const std::vector<double> su = geometricCuts(strips, std::pow(4.0, strips - 1));
  const std::vector<double> sv = geometricCuts(cells, 1e6);
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = -1; side <= 1; side += 2) {
      auto point = [&](double u, double v) {
        float c[3];
        c[axis] = float(side);
        c[(axis + 1) % 3] = float(2 * u - 1);
        c[(axis + 2) % 3] = float(2 * v - 1);
        return Vec3f(c[0], c[1], c[2]);
      };
      for (int i = 0; i < strips; ++i) {
        ShapeDescription s;
        for (int j = 0; j < cells; ++j) {
          addQuad(&s, point(su[i], sv[j]), point(su[i + 1], sv[j]), point(su[i + 1], sv[j + 1]),
                  point(su[i], sv[j + 1]), Vec3f(0.0f));
        }
        makeFurnace(&s, 0, kFurnaceLe);
        d.shapes.push_back(s);
      }
    }
  }
  return d;
}

// The furnace box with a glass slab (a box of index `ior`) between the camera and the walls it
// sees; paths unbounded, since every crossing of the glass takes edges. Seen from outside the
// glass the radiance is the furnace's: the n^2 a beam gains on entering glass of index n it
// loses on leaving (Veach 1997, sec. 5.2).
// With alpha > 0 the slab is a rough dielectric (GGX) instead: at alpha 1e-4 it is lossless
// within noise, and the furnace's answer holds; rougher, microfacet shadowing loses light.
inline SceneDescription glassInFurnace(float ior, int size = 16, float alpha = 0) {
  SceneDescription d = furnaceBox(1, -1, kFurnaceLe, size);
  BsdfDescription glass;
  glass.type =
      alpha > 0 ? BsdfDescription::Type::RoughDielectric : BsdfDescription::Type::Dielectric;
  glass.distribution = MicrofacetDistribution::GGX;
  glass.alpha = alpha;
  glass.intIOR = ior;
  glass.extIOR = 1;
  d.bsdfs.push_back(glass);
  ShapeDescription slab = box(Vec3f(-0.6f, -0.7f, 0.1f), Vec3f(0.9f, 0.8f, 0.4f), true);
  slab.bsdf = 1;
  d.shapes.push_back(slab);
  return d;
}

// The furnace with the camera at the centre of a glass ball: every camera ray meets the glass
// at normal incidence, so none is trapped by total internal reflection, and the camera sees
// ior^2 times the furnace's radiance. (In a glass box, directions that reflect totally at every
// face never see out and stay dark.)
inline SceneDescription cameraInGlassBall(float ior, int size = 16) {
  SceneDescription d = glassInFurnace(ior, size);
  d.shapes.pop_back();
  ShapeDescription ball;
  ball.type = ShapeDescription::Type::Sphere;
  ball.center = Vec3f(d.camera.toWorld.m[0][3], d.camera.toWorld.m[1][3], d.camera.toWorld.m[2][3]);
  ball.radius = 0.3f;
  ball.bsdf = 1;
  d.shapes.push_back(ball);
  return d;
}

// --- A floor under a spherical light (direct light only) ---------------------------------------

struct FloorLight {
  float rho = 0.5f, le = 10, radius = 0.25f;
  Vec3f center{0, 2, 0};
};

// The floor y = 0 (diffuse rho, facing +y) and the light; the camera at `eye` looking at `at`.
inline SceneDescription floorUnderSphere(const FloorLight& f, const Vec3f& eye, const Vec3f& at,
                                         float fov, int size) {
  SceneDescription d;
  d.camera.toWorld = Matrix4::lookAt(eye, at, Vec3f(0, 1, 0));
  d.camera.fovDegrees = fov;
  d.camera.width = d.camera.height = size;
  d.camera.filter = FilterType::Box;
  d.maxDepth = 2;
  d.bsdfs.push_back(diffuse(f.rho, false));
  d.bsdfs.push_back(diffuse(0, false));
  ShapeDescription plane;
  const float r = 1000;
  addQuad(&plane, {-r, 0, -r}, {r, 0, -r}, {r, 0, r}, {-r, 0, r}, Vec3f(0, 1, 0));
  plane.bsdf = 0;
  d.shapes.push_back(plane);
  ShapeDescription light;
  light.type = ShapeDescription::Type::Sphere;
  light.center = f.center;
  light.radius = f.radius;
  light.bsdf = 1;
  light.isEmitter = true;
  light.radiance = Spectrum(f.le);
  d.shapes.push_back(light);
  return d;
}

// The floor's radiance at p: rho / pi * pi Le r^2 cos(theta) / d^2.
inline double floorRadiance(const FloorLight& f, const Vec3f& p) {
  const double dx = f.center.x - p.x, dy = f.center.y - p.y, dz = f.center.z - p.z;
  const double dist2 = dx * dx + dy * dy + dz * dz;
  return f.rho * f.le * f.radius * f.radius * (dy / std::sqrt(dist2)) / dist2;
}

// --- Rooms lit by a sphere ---------------------------------------------------------------------

struct Room {
  float scale = 1;
  float lightRadius = 0.05f;
  float lightRadiance = 50;  // for lightRadius 0.05; scaled to keep the power
  bool plate = true;         // a thin square plate hovering just above the floor
  float plateGap = 0.01f;
  bool tiltedNormals = false;  // floor shading normals 50 degrees from the geometric normal
  float sealedHole = 0;        // > 0: the light inside a closed box with a hole of this side
  // The plate's material, when not diffuse (a mirror, a rough metal); the camera sees the
  // ceiling in it.
  std::optional<BsdfDescription> plateBsdf;
  float plateSize = 0.3f;  // half the plate's side
  // > 0: a smooth glass slab of this index in front of the camera, filling its view.
  float slabIor = 0;
  // > 0: a glass ball of this index on the floor under the light, a coarse mesh with the
  // sphere's normals (smoothSphere): its caustic on the floor, and the floor seen through it.
  float ballIor = 0;
};

// A 2 x 2 x 2 room (diffuse walls), a sphere light near the ceiling, a camera below it looking
// down at the floor (the light out of view), all scaled by room.scale.
inline SceneDescription room(const Room& r, int size = 16, int maxDepth = 4) {
  const float s = r.scale;
  SceneDescription d;
  d.camera.toWorld =
      Matrix4::lookAt(Vec3f(0.1f, 0.6f, -0.9f) * s, Vec3f(0.0f, -1.0f, 0.2f) * s, Vec3f(0, 1, 0));
  d.camera.fovDegrees = 60;
  d.camera.width = d.camera.height = size;
  d.maxDepth = maxDepth;
  d.bsdfs.push_back(diffuse(0.6f, false));  // walls
  d.bsdfs.push_back(diffuse(0.0f, false));  // the light's surface: black
  d.bsdfs.push_back(diffuse(0.4f, true));   // plate and light box
  ShapeDescription walls = box(Vec3f(-s), Vec3f(s));
  walls.bsdf = 0;
  if (r.tiltedNormals) {
    // Shading normals of the floor's vertices leaning 50 degrees (alternately) from +y.
    walls.normals.resize(walls.positions.size());
    for (size_t i = 0; i < walls.positions.size(); ++i) walls.normals[i] = Vec3f(0.0f);
    for (size_t t = 0; t < walls.indices.size(); t += 3) {
      const Vec3f &a = walls.positions[walls.indices[t]],
                  &b = walls.positions[walls.indices[t + 1]],
                  &c = walls.positions[walls.indices[t + 2]];
      Vec3f n = normalize(cross(b - a, c - a));
      for (int k = 0; k < 3; ++k) walls.normals[walls.indices[t + k]] = n;
    }
    for (size_t i = 0; i < walls.positions.size(); ++i) {
      if (walls.normals[i].y > 0.5f) {  // the floor's (faces are not shared between walls)
        const float lean = 50 * kPi / 180, sign = (i % 2) ? 1.0f : -1.0f;
        walls.normals[i] = Vec3f(sign * std::sin(lean), std::cos(lean), 0);
      }
    }
  }
  d.shapes.push_back(walls);
  if (r.plate) {
    ShapeDescription plate;
    const float y = -1 + r.plateGap;
    addQuad(&plate, Vec3f(-r.plateSize, y, -r.plateSize) * s,
            Vec3f(r.plateSize, y, -r.plateSize) * s, Vec3f(r.plateSize, y, r.plateSize) * s,
            Vec3f(-r.plateSize, y, r.plateSize) * s, Vec3f(0, 1, 0) * s);
    plate.bsdf = 2;
    if (r.plateBsdf) {
      d.bsdfs.push_back(*r.plateBsdf);
      plate.bsdf = int(d.bsdfs.size()) - 1;
    }
    d.shapes.push_back(plate);
  }
  const Vec3f lightCenter(0.2f, 0.7f, 0.1f);
  if (r.sealedHole > 0) {
    // A box around the light with one square hole of side sealedHole in its floor.
    ShapeDescription housing;
    const float e = 0.15f, h = r.sealedHole / 2;
    const Vec3f c = lightCenter, lo = c - Vec3f(e), hi = c + Vec3f(e);
    auto add = [&](Vec3f p0, Vec3f p1, Vec3f p2, Vec3f p3) {
      addQuad(&housing, p0 * s, p1 * s, p2 * s, p3 * s, lightCenter * s);
    };
    add({lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z});
    add({lo.x, lo.y, lo.z}, {lo.x, hi.y, lo.z}, {lo.x, hi.y, hi.z}, {lo.x, lo.y, hi.z});
    add({hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {hi.x, lo.y, hi.z});
    add({lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z});
    add({lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z});
    // The floor of the housing: four quads around the hole.
    const float y = lo.y;
    add({lo.x, y, lo.z}, {hi.x, y, lo.z}, {hi.x, y, c.z - h}, {lo.x, y, c.z - h});
    add({lo.x, y, c.z + h}, {hi.x, y, c.z + h}, {hi.x, y, hi.z}, {lo.x, y, hi.z});
    add({lo.x, y, c.z - h}, {c.x - h, y, c.z - h}, {c.x - h, y, c.z + h}, {lo.x, y, c.z + h});
    add({c.x + h, y, c.z - h}, {hi.x, y, c.z - h}, {hi.x, y, c.z + h}, {c.x + h, y, c.z + h});
    housing.bsdf = 2;
    d.shapes.push_back(housing);
  }
  if (r.slabIor > 0) {
    // A slab 0.05 thick across the camera's view, 0.15 in front of it: every camera ray crosses
    // it, and no ray from the light to what the camera sees does.
    d.bsdfs.push_back(glass(r.slabIor));
    const Matrix4& c = d.camera.toWorld;
    const Vec3f eye = Vec3f(c.m[0][3], c.m[1][3], c.m[2][3]) / s;  // at scale 1
    const Vec3f forward = normalize(c.applyVector(Vec3f(0, 0, 1)));
    const Vec3f right = normalize(c.applyVector(Vec3f(1, 0, 0)));
    const Vec3f up = normalize(c.applyVector(Vec3f(0, 1, 0)));
    ShapeDescription slab;
    const Vec3f center = eye + forward * 0.175f;
    const float half = 0.15f, depth = 0.025f;
    const Vec3f corner[8] = {center + (-half * right - half * up - depth * forward),
                             center + (half * right - half * up - depth * forward),
                             center + (half * right + half * up - depth * forward),
                             center + (-half * right + half * up - depth * forward),
                             center + (-half * right - half * up + depth * forward),
                             center + (half * right - half * up + depth * forward),
                             center + (half * right + half * up + depth * forward),
                             center + (-half * right + half * up + depth * forward)};
    // Six faces facing away from the slab's centre (scaled with the room).
    const int faces[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4},
                             {3, 2, 6, 7}, {0, 3, 7, 4}, {1, 2, 6, 5}};
    for (const auto& f : faces) {
      const Vec3f a = corner[f[0]] * s, b = corner[f[1]] * s, cc = corner[f[2]] * s,
                  e = corner[f[3]] * s;
      const Vec3f mid = (a + b + cc + e) * 0.25f;
      addQuad(&slab, a, b, cc, e, mid + (mid - center * s));
    }
    slab.bsdf = int(d.bsdfs.size()) - 1;
    d.shapes.push_back(slab);
  }
  if (r.ballIor > 0) {
    d.bsdfs.push_back(glass(r.ballIor));
    ShapeDescription ball = smoothSphere(Vec3f(0.15f, -0.6f, 0.2f) * s, 0.35f * s, 4, 6);
    ball.bsdf = int(d.bsdfs.size()) - 1;
    d.shapes.push_back(ball);
  }
  ShapeDescription light;
  light.type = ShapeDescription::Type::Sphere;
  light.center = lightCenter * s;
  light.radius = r.lightRadius * s;
  light.bsdf = 1;
  light.isEmitter = true;
  const float ratio = 0.05f / r.lightRadius;
  light.radiance = Spectrum(r.lightRadiance * ratio * ratio);
  d.shapes.push_back(light);
  return d;
}

// A metal plate on the floor in which the camera sees the ceiling, lit by a larger light (a
// small one reflected onto the ceiling makes caustics seen in the mirror that only paths
// hitting the light can carry).
inline Room metalPlateRoom(BsdfDescription::Type type, float alpha) {
  BsdfDescription metal;
  metal.type = type;
  metal.distribution = MicrofacetDistribution::GGX;
  metal.alpha = alpha;
  metal.eta = Spectrum(1.66f, 0.88f, 0.52f);  // gold, roughly: the Fresnel term varies with angle
  metal.k = Spectrum(1.95f, 2.2f, 2.6f);
  Room r;
  r.plateBsdf = metal;
  r.plateSize = 0.5f;
  r.lightRadius = 0.25f;
  return r;
}

// A room lit by a square light on its ceiling (facing down), half of which a black plate covers
// `gap` below it; with `coveredEmits` false, only the uncovered half emits. The two render alike
// (the covered half's light escapes only through the slit, at grazing angles), unless shadow
// rays stop short of the light by more than the gap.
inline SceneDescription coveredLightRoom(bool coveredEmits, float gap = 1e-4f, int size = 16) {
  Room r;
  r.plate = false;
  SceneDescription d = room(r, size);
  d.shapes.pop_back();  // the sphere
  const float y = 0.999f, a = 0.3f;
  ShapeDescription open, covered, cover;
  addQuad(&open, Vec3f(-a, y, -a), Vec3f(0, y, -a), Vec3f(0, y, a), Vec3f(-a, y, a),
          Vec3f(0, -1, 0));
  addQuad(&covered, Vec3f(0, y, -a), Vec3f(a, y, -a), Vec3f(a, y, a), Vec3f(0, y, a),
          Vec3f(0, -1, 0));
  // The cover overhangs the covered half by 0.01 on its three open sides.
  const float c = y - gap, o = 0.01f;
  addQuad(&cover, Vec3f(0, c, -a - o), Vec3f(a + o, c, -a - o), Vec3f(a + o, c, a + o),
          Vec3f(0, c, a + o), Vec3f(0, -1, 0));
  open.bsdf = covered.bsdf = 1;  // black
  d.bsdfs.push_back(diffuse(0.0f, true));
  cover.bsdf = int(d.bsdfs.size()) - 1;
  open.isEmitter = true;
  open.radiance = Spectrum(20.0f);
  covered.isEmitter = coveredEmits;
  covered.radiance = Spectrum(coveredEmits ? 20.0f : 0.0f);
  d.shapes.push_back(open);
  d.shapes.push_back(covered);
  d.shapes.push_back(cover);
  return d;
}

// The room without any light.
inline SceneDescription unlitRoom(int size = 16) {
  SceneDescription d = room(Room{}, size);
  d.shapes.pop_back();
  return d;
}

// --- Degenerate triangles, through the loader --------------------------------------------------

// A furnace box written as Mitsuba XML with the walls in an OBJ file; with `degenerate`, the OBJ
// also holds a repeated-vertex, a repeated-position, a collinear and a needle triangle on the
// walls; with `ply`, the walls are a binary PLY instead. Returns the XML's path.
inline std::string furnaceBoxFile(bool degenerate, int maxDepth, bool ply = false) {
  namespace fs = std::filesystem;
  const std::string dir = (fs::temp_directory_path() /
                           (ply ? "stiff_ply" : (degenerate ? "stiff_degenerate" : "stiff_clean")))
                              .string();
  fs::create_directories(dir);
  SceneDescription d = furnaceBox(1, maxDepth);
  const ShapeDescription& walls = d.shapes[0];
  if (ply) {
    // Binary little-endian PLY (this machine's order), written byte for byte.
    std::ofstream out(dir + "/walls.ply", std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << walls.positions.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face "
        << walls.indices.size() / 3 << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const Vec3f& p : walls.positions)
      out.write(reinterpret_cast<const char*>(&p.x), 3 * sizeof(float));
    for (size_t t = 0; t < walls.indices.size(); t += 3) {
      const unsigned char three = 3;
      out.write(reinterpret_cast<const char*>(&three), 1);
      for (int k = 0; k < 3; ++k) {
        const int32_t i = int32_t(walls.indices[t + size_t(k)]);
        out.write(reinterpret_cast<const char*>(&i), sizeof(i));
      }
    }
  } else {
    std::ofstream obj(dir + "/walls.obj");
    obj.precision(9);
    for (const Vec3f& p : walls.positions) obj << "v " << p.x << " " << p.y << " " << p.z << "\n";
    const size_t n = walls.positions.size();
    if (degenerate) {
      obj << "v -1 -0.5 0.25\n";  // n + 1: a copy of no vertex, on the x = -1 wall
      obj << "v -1 -0.5 0.25\n";  // n + 2: the same position again
      obj << "v -1 0.5 -0.25\n";  // n + 3
      obj << "v -1 0 0\n";        // n + 4: midway between n + 1 and n + 3
      obj << "v -1 5e-7 1e-6\n";  // n + 5: 1.1e-6 off the line through n + 1, n + 3
    }
    for (size_t t = 0; t < walls.indices.size(); t += 3) {
      obj << "f " << walls.indices[t] + 1 << " " << walls.indices[t + 1] + 1 << " "
          << walls.indices[t + 2] + 1 << "\n";
      if (degenerate && t == 6) {  // among the others, not at the end
        obj << "f " << n + 1 << " " << n + 1 << " " << n + 3 << "\n";  // repeated vertex
        obj << "f " << n + 1 << " " << n + 2 << " " << n + 3 << "\n";  // repeated position
        obj << "f " << n + 1 << " " << n + 4 << " " << n + 3 << "\n";  // collinear
        obj << "f " << n + 1 << " " << n + 3 << " " << n + 4 << "\n";  // collinear, other order
      }
    }
    if (degenerate) {
      // A needle: (n+1, n+3, n+5) has height 1.1e-6 over a base of 1.1.
      obj << "f " << n + 1 << " " << n + 3 << " " << n + 5 << "\n";
    }
  }
  const Matrix4& m = d.camera.toWorld;
  std::ofstream xml(dir + "/scene.xml");
  xml.precision(9);
  xml << "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n"
      << "  <integrator type=\"path\"><integer name=\"maxDepth\" value=\"" << maxDepth
      << "\"/></integrator>\n"
      << "  <sensor type=\"perspective\">\n    <float name=\"fov\" value=\"" << d.camera.fovDegrees
      << "\"/>\n    <transform name=\"toWorld\"><matrix value=\"";
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) xml << m.m[i][j] << (i == 3 && j == 3 ? "" : " ");
  xml << "\"/></transform>\n    <film type=\"hdrfilm\"><integer name=\"width\" value=\""
      << d.camera.width << "\"/><integer name=\"height\" value=\"" << d.camera.height
      << "\"/></film>\n  </sensor>\n"
      << "  <bsdf type=\"twosided\" id=\"wall\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
         "value=\""
      << kFurnaceAlbedo << "\"/></bsdf></bsdf>\n"
      << "  <shape type=\"" << (ply ? "ply" : "obj") << "\"><string name=\"filename\" value=\""
      << (ply ? "walls.ply" : "walls.obj")
      << "\"/><boolean name=\"faceNormals\" value=\"true\"/><ref id=\"wall\"/>\n"
      << "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"" << kFurnaceLe.x << " "
      << kFurnaceLe.y << " " << kFurnaceLe.z << "\"/></emitter>\n  </shape>\n</scene>\n";
  return dir + "/scene.xml";
}

}  // namespace stiff
}  // namespace farm
