// The scene's geometry queries: transmittance through clear media as visibility, and which
// specular shapes are smooth. Light sampling's are lights_test.cpp's.
#include "common/scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/sampling/rng.h"
#include "common/sampling/warp.h"
#include "common/scene/loaders/scene_loader.h"
#include "common/scene/test_scenes.h"

namespace farm {
namespace {

// A room (walls facing in) with a ball, seen through a box of clear medium (sigma 0) that
// only null boundaries bound, or with no box: between any two wall points the transmittance
// through the box must be the visibility without it. The box's faces cross most segments; a
// ray that did not aim at the offset end point itself would clip the end's own wall.
TEST(Scene, TransmittanceThroughClearMediaIsVisibility) {
  SceneDescription room;
  BsdfDescription white;
  room.bsdfs.push_back(white);
  const Vec3f lo(-1, 0, -3.5f), hi(1, 2, 1);
  const Vec3f e = hi - lo, x(e.x, 0, 0), y(0, e.y, 0), z(0, 0, e.z);
  // Inward normals: each face's edges in the opposite order to an outward box's.
  room.shapes.push_back(quadShape(lo, x, y, 0));                       // -z face
  room.shapes.push_back(quadShape(Vec3f(lo.x, lo.y, hi.z), y, x, 0));  // +z
  room.shapes.push_back(quadShape(lo, z, x, 0));                       // floor
  room.shapes.push_back(quadShape(Vec3f(lo.x, hi.y, lo.z), x, z, 0));  // ceiling
  room.shapes.push_back(quadShape(lo, y, z, 0));                       // -x
  room.shapes.push_back(quadShape(Vec3f(hi.x, lo.y, lo.z), z, y, 0));  // +x
  room.shapes.push_back(sphereShape(Vec3f(-0.4f, 0.26f, -0.1f), 0.25f, 0));
  SceneDescription withBox = room;
  withBox.media.push_back(MediumDescription{});  // sigma_a = sigma_s = 0
  const Vec3f blo(-0.98f, 0.01f, -1.0f), bhi(0.98f, 1.0f, 0.98f);
  const Vec3f be = bhi - blo, bx(be.x, 0, 0), by(0, be.y, 0), bz(0, 0, be.z);
  const ShapeDescription faces[6] = {
      quadShape(blo, by, bx, -1), quadShape(Vec3f(blo.x, blo.y, bhi.z), bx, by, -1),
      quadShape(blo, bx, bz, -1), quadShape(Vec3f(blo.x, bhi.y, blo.z), bz, bx, -1),
      quadShape(blo, bz, by, -1), quadShape(Vec3f(bhi.x, blo.y, blo.z), by, bz, -1)};
  for (ShapeDescription f : faces) {
    f.hasMediumInterface = true;
    f.interiorMedium = 0;
    f.nullBoundary = true;
    withBox.shapes.push_back(f);
  }
  const Scene plain(room), boxed(withBox);
  ASSERT_TRUE(boxed.hasMedia());
  Rng rng(5, 5);
  IndependentSampler sampler(&rng);
  auto wallPoint = [&](SurfaceHit* h) {
    for (;;) {
      Ray r;
      r.o = Vec3f(rng.nextFloat() * 1.6f - 0.8f, 0.05f + rng.nextFloat() * 1.8f,
                  -2 + 2.5f * rng.nextFloat());
      r.d = squareToUniformSphere({rng.nextFloat(), rng.nextFloat()});
      if (plain.intersect(r, h)) return;
    }
  };
  int visibleCount = 0, mismatches = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    SurfaceHit a, b;
    wallPoint(&a);
    wallPoint(&b);
    // Points on one plane see each other only at grazing angles, where it does not matter.
    if (std::fabs(dot(a.ng, b.ng)) > 0.999f && std::fabs(dot(b.p - a.p, a.ng)) < 1e-4f) continue;
    const bool visible = plain.visible(a.p, a.ng, b.p, b.ng);
    const Spectrum T = boxed.transmittance(a.p, a.ng, b.p, b.ng, -1, sampler, kCameraStream);
    visibleCount += visible;
    if (visible != (T.x == 1 && T.y == 1 && T.z == 1) || (!visible && !isBlack(T))) ++mismatches;
  }
  EXPECT_GT(visibleCount, n / 2);
  EXPECT_EQ(mismatches, 0);
}

// An octahedron about the origin, radius 1: shared vertices (six), or split (three a face, as a
// flat-shaded export writes it); vertex normals none, the corners' directions (smooth), or each
// face's own (faceted however the vertices lie).
ShapeDescription octahedron(bool split, int normals, int bsdf) {
  const Vec3f v[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const uint32_t faces[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  ShapeDescription s;
  s.bsdf = bsdf;
  if (!split) {
    for (const Vec3f& p : v) s.positions.push_back(p), s.normals.push_back(normalize(p));
    for (const auto& f : faces) s.indices.insert(s.indices.end(), f, f + 3);
    s.faceNormals = normals == 2;
  } else {
    for (const auto& f : faces) {
      const Vec3f faceNormal = normalize(cross(v[f[1]] - v[f[0]], v[f[2]] - v[f[0]]));
      for (uint32_t c : f) {
        s.indices.push_back(uint32_t(s.positions.size()));
        s.positions.push_back(v[c]);
        s.normals.push_back(normals == 2 ? faceNormal : normalize(v[c]));
      }
    }
  }
  if (normals == 0) s.normals.clear();
  return s;
}

// Scene::smoothSpecularShape, where manifold next-event estimation may walk (its paths through
// the others stay with BDPT): a sphere, a plane and a smooth-shaded mesh are smooth whether or
// not a flat-shaded export split their vertices; a curved mesh with its faces' normals is not,
// nor is anything diffuse. And the water caustic's waves: smooth with their vertex normals (all
// vertical there), faceted with face normals; its flat front face smooth either way.
TEST(Scene, SmoothSpecularShapesAreTheOnesWithoutCreases) {
  SceneDescription d = whiteFurnace(0.5f, 4);
  BsdfDescription glass;
  glass.type = BsdfDescription::Type::Dielectric;
  d.bsdfs.push_back(glass);
  const int g = int(d.bsdfs.size()) - 1;
  struct Case {
    const char* name;
    ShapeDescription shape;
    bool smooth;
  };
  const Case cases[] = {
      {"sphere", sphereShape(Vec3f(0.0f), 0.5f, g), true},
      {"quad", quadShape(Vec3f(-1, -1, 0.5f), Vec3f(2, 0, 0), Vec3f(0, 2, 0), g), true},
      {"diffuse quad", quadShape(Vec3f(-1, -1, 0.5f), Vec3f(2, 0, 0), Vec3f(0, 2, 0), 0), false},
      {"octahedron, face normals", octahedron(false, 0, g), false},
      {"octahedron, face normals forced", octahedron(false, 2, g), false},
      {"octahedron, vertex normals", octahedron(false, 1, g), true},
      {"split octahedron, no normals", octahedron(true, 0, g), false},
      {"split octahedron, smooth normals", octahedron(true, 1, g), true},
      {"split octahedron, faces' normals", octahedron(true, 2, g), false},
  };
  for (const Case& c : cases) {
    SceneDescription one = d;
    one.shapes.push_back(c.shape);
    Scene scene(one);
    EXPECT_FALSE(scene.smoothSpecularShape(0)) << "the diffuse furnace";
    EXPECT_EQ(scene.smoothSpecularShape(1), c.smooth) << c.name;
    EXPECT_EQ(scene.hasSmoothSpecularShape(), c.smooth) << c.name;
  }

  SceneDescription water =
      loadSceneDescription(std::string(FARM_SHARED_DIR) + "/scenes/water-caustic/scene.xml");
  int waves = -1, front = -1;
  for (int i = 0; i < int(water.shapes.size()); ++i) {
    const ShapeDescription& s = water.shapes[size_t(i)];
    if (s.faceNormals && !s.indices.empty()) front = i;
    if (!s.normals.empty() && !s.faceNormals) waves = i;
  }
  ASSERT_GE(waves, 0);
  ASSERT_GE(front, 0);
  {
    Scene scene(water);
    EXPECT_TRUE(scene.smoothSpecularShape(waves));
    EXPECT_TRUE(scene.smoothSpecularShape(front));
  }
  water.shapes[size_t(waves)].faceNormals = true;
  Scene faceted(water);
  EXPECT_FALSE(faceted.smoothSpecularShape(waves));
  EXPECT_TRUE(faceted.smoothSpecularShape(front));
}

}  // namespace
}  // namespace farm
