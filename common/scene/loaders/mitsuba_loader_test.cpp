#include "common/scene/loaders/mitsuba_loader.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "common/math/transform.h"
#include "common/scene/film_override.h"
#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

const std::string kShared = FARM_SHARED_DIR;

std::string scenePath(const std::string& name) {
  return kShared + "/scenes/" + name + "/scene.xml";
}

void expectNear(const Vec3f& a, const Vec3f& b, float tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

Vec3f triangleNormal(const ShapeDescription& s, size_t t) {
  const Vec3f& a = s.positions[s.indices[3 * t]];
  const Vec3f& b = s.positions[s.indices[3 * t + 1]];
  const Vec3f& c = s.positions[s.indices[3 * t + 2]];
  return cross(b - a, c - a);
}

// Wraps body lines in a scene; the first body line is line 3 of the file.
std::string sceneXml(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n" + body + "</scene>\n";
}

// ---- Matrix4 ----

TEST(Matrix4Test, InverseOfComposite) {
  Matrix4 m = Matrix4::translate({1, -2, 3}) * Matrix4::rotate({1, 2, 3}, 37) *
              Matrix4::scale({2, 0.5f, 3});
  Matrix4 p = m * m.inverse();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(p.m[i][j], i == j ? 1.0 : 0.0, 1e-12);
  Vec3f q{0.3f, -1.7f, 2.2f};
  expectNear(m.inverse().applyPoint(m.applyPoint(q)), q, 1e-5f);
}

TEST(Matrix4Test, SingularInverseIsNotFinite) {
  EXPECT_FALSE(Matrix4::scale({1, 0, 1}).inverse().isFinite());
  Matrix4 m = Matrix4::identity();
  m.m[1] = m.m[0];  // two equal rows
  EXPECT_FALSE(m.inverse().isFinite());
  EXPECT_TRUE(Matrix4::scale({1e-3f, 1e3f, 1}).inverse().isFinite());
  // Singular in exact arithmetic, not in floating point elimination.
  Matrix4 n = Matrix4::identity();
  const double rows[3][3] = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) n.m[i][j] = rows[i][j] * 0.1;
  EXPECT_FALSE(n.inverse().isFinite());
  // Huge translations with tiny scales are fine.
  Matrix4 far = Matrix4::translate({1e8f, -3e7f, 5e6f}) * Matrix4::scale(Vec3f(1e-7f));
  Matrix4 farInv = far.inverse();
  ASSERT_TRUE(farInv.isFinite());
  // (p - t) / s: entries 1 / s and -t / s (of the float-rounded s and t).
  EXPECT_NEAR(farInv.m[0][0] * double(1e-7f), 1.0, 1e-12);
  EXPECT_NEAR(farInv.m[0][3] * double(1e-7f) / -double(1e8f), 1.0, 1e-12);
}

TEST(Matrix4Test, RotateTranslateScale) {
  expectNear(Matrix4::rotate({0, 0, 1}, 90).applyVector({1, 0, 0}), {0, 1, 0}, 1e-6f);
  expectNear(Matrix4::rotate({1, 0, 0}, 90).applyVector({0, 1, 0}), {0, 0, 1}, 1e-6f);
  expectNear(Matrix4::translate({1, 2, 3}).applyPoint({1, 1, 1}), {2, 3, 4}, 0);
  expectNear(Matrix4::translate({1, 2, 3}).applyVector({1, 1, 1}), {1, 1, 1}, 0);
  expectNear(Matrix4::scale({2, 3, 4}).applyPoint({1, 1, 1}), {2, 3, 4}, 0);
  Matrix4 t = Matrix4::rotate({0, 1, 0}, 30).transpose() * Matrix4::rotate({0, 1, 0}, 30);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(t.m[i][i], 1.0, 1e-12);
}

TEST(Matrix4Test, ApplyNormalIsInverseTranspose) {
  Matrix4 m = Matrix4::scale({2, 1, 1});
  // Not normalized: (M^-1)^T (1, 1, 0) = (0.5, 1, 0).
  expectNear(m.applyNormal({1, 1, 0}), {0.5f, 1, 0}, 1e-6f);
  // Stays perpendicular to transformed tangents under a general transform.
  Matrix4 g = Matrix4::rotate({1, 1, 0}, 20) * Matrix4::scale({3, 0.2f, 1.5f});
  Vec3f n{0.2f, 0.9f, -0.4f}, t1 = cross(n, {1, 0, 0}), t2 = cross(n, t1);
  Vec3f nw = g.applyNormal(n);
  EXPECT_NEAR(dot(nw, g.applyVector(t1)), 0, 1e-5);
  EXPECT_NEAR(dot(nw, g.applyVector(t2)), 0, 1e-5);
}

TEST(Matrix4Test, LookAtMitsubaConvention) {
  Matrix4 m = Matrix4::lookAt({1, 2, 3}, {1, 2, 2}, {0, 1, 0});
  expectNear(m.applyPoint({0, 0, 0}), {1, 2, 3}, 0);
  expectNear(m.applyVector({0, 0, 1}), {0, 0, -1}, 1e-6f);  // looks down its +z
  expectNear(m.applyVector({0, 1, 0}), {0, 1, 0}, 1e-6f);   // +y up
  expectNear(m.applyVector({1, 0, 0}), {-1, 0, 0}, 1e-6f);  // +x = up x dir
  EXPECT_FALSE(Matrix4::lookAt({0, 0, 0}, {0, 1, 0}, {0, 1, 0}).isFinite());
}

// ---- The shared scenes ----

TEST(MitsubaLoaderTest, CornellBox) {
  SceneDescription s = loadMitsubaScene(scenePath("cornell-box"));
  EXPECT_EQ(s.sourcePath, scenePath("cornell-box"));
  ASSERT_EQ(s.shapes.size(), 8u);
  ASSERT_EQ(s.bsdfs.size(), 8u);
  EXPECT_EQ(s.maxDepth, 65);
  EXPECT_FLOAT_EQ(s.camera.fovDegrees, 19.5f);
  EXPECT_EQ(s.camera.fovAxis, FovAxis::X);
  EXPECT_EQ(s.camera.width, 1024);
  EXPECT_EQ(s.camera.height, 1024);
  EXPECT_EQ(s.camera.filter, FilterType::Tent);
  expectNear(s.camera.toWorld.applyPoint({0, 0, 0}), {0, 1, 6.8f}, 1e-6f);
  expectNear(s.camera.toWorld.applyVector({0, 0, 1}), {0, 0, -1}, 1e-6f);

  int emitters = 0;
  for (const ShapeDescription& shape : s.shapes) {
    EXPECT_EQ(shape.type, ShapeDescription::Type::TriangleMesh);
    ASSERT_GE(shape.bsdf, 0);
    ASSERT_LT(shape.bsdf, 8);
    EXPECT_TRUE(s.bsdfs[shape.bsdf].twoSided);
    EXPECT_EQ(s.bsdfs[shape.bsdf].type, BsdfDescription::Type::Diffuse);
    emitters += shape.isEmitter;
  }
  EXPECT_EQ(emitters, 1);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(s.shapes[i].indices.size(), 6u) << i;
  EXPECT_EQ(s.shapes[5].indices.size(), 36u);
  EXPECT_EQ(s.shapes[6].indices.size(), 36u);
  EXPECT_EQ(s.bsdfs[s.shapes[0].bsdf].id, "Floor");
  expectNear(s.bsdfs[0].reflectance, {0.63f, 0.065f, 0.05f}, 0);  // LeftWall
  EXPECT_EQ(s.shapes[0].origin, "scene.xml:67 (rectangle)");

  // The light: rectangle with
  //   [0.235 -1.66e-8 -7.8e-9 -0.005; -2.05e-8 3.9e-9 -0.0893 1.98; 2.05e-8 0.19 8.3e-9 -0.03]
  // maps local (x, y, 0) to (0.235 x - 0.005, 1.98, 0.19 y - 0.03), up to 1e-7.
  const ShapeDescription& light = s.shapes[7];
  ASSERT_TRUE(light.isEmitter);
  expectNear(light.radiance, {17, 12, 4}, 0);
  EXPECT_EQ(s.bsdfs[light.bsdf].id, "Light");
  expectNear(s.bsdfs[light.bsdf].reflectance, Vec3f(0.0f), 0);
  ASSERT_EQ(light.positions.size(), 4u);
  const Vec3f expected[4] = {{-0.24f, 1.98f, -0.22f},
                             {0.23f, 1.98f, -0.22f},
                             {0.23f, 1.98f, 0.16f},
                             {-0.24f, 1.98f, 0.16f}};
  for (const Vec3f& e : expected) {
    bool found = false;
    for (const Vec3f& p : light.positions) found |= length(p - e) < 1e-5f;
    EXPECT_TRUE(found) << e.x << " " << e.y << " " << e.z;
  }
  // Its normal: the plane's +z through the inverse transpose points down into the box.
  ASSERT_EQ(light.normals.size(), 4u);
  for (const Vec3f& n : light.normals) expectNear(n, {0, -1, 0}, 1e-5f);
  for (size_t t = 0; t < 2; ++t) EXPECT_GT(dot(triangleNormal(light, t), light.normals[0]), 0);
}

// Mitsuba's Shape::configure: a plain shape without a BSDF gets a diffuse one of reflectance
// 0.5, an emitter an absorbing one (a light does not reflect), a medium boundary none.
TEST(MitsubaLoaderTest, ShapesWithoutABsdfGetMitsubasDefaults) {
  TempDir dir;
  const SceneDescription s = loadMitsubaScene(dir.write("d.xml", sceneXml(R"(<shape type="cube"/>
<shape type="rectangle"><emitter type="area"/></shape>
<medium type="homogeneous" id="m"/>
<shape type="sphere"><ref name="interior" id="m"/></shape>
)")));
  ASSERT_EQ(s.shapes.size(), 3u);
  const BsdfDescription& plain = s.bsdfs.at(size_t(s.shapes[0].bsdf));
  EXPECT_EQ(plain.type, BsdfDescription::Type::Diffuse);
  EXPECT_FLOAT_EQ(plain.reflectance.x, 0.5f);
  const BsdfDescription& light = s.bsdfs.at(size_t(s.shapes[1].bsdf));
  EXPECT_EQ(light.type, BsdfDescription::Type::Diffuse);
  EXPECT_TRUE(isBlack(light.reflectance));
  EXPECT_TRUE(s.shapes[1].isEmitter);
  EXPECT_TRUE(s.shapes[2].nullBoundary);
}

TEST(MitsubaLoaderTest, CubeHasTwelveOutwardTriangles) {
  SceneDescription s = loadMitsubaScene(scenePath("cornell-box"));
  for (int i : {5, 6}) {
    const ShapeDescription& cube = s.shapes[i];
    ASSERT_EQ(cube.indices.size(), 36u);
    EXPECT_TRUE(cube.faceNormals);
    EXPECT_TRUE(cube.normals.empty());
    Vec3f center(0.0f);
    for (const Vec3f& p : cube.positions) center += p;
    center /= float(cube.positions.size());
    for (size_t t = 0; t < 12; ++t) {
      Vec3f c = (cube.positions[cube.indices[3 * t]] + cube.positions[cube.indices[3 * t + 1]] +
                 cube.positions[cube.indices[3 * t + 2]]) /
                3.0f;
      EXPECT_GT(dot(triangleNormal(cube, t), c - center), 0) << "cube " << i << " triangle " << t;
    }
  }
  // The short box's toWorld maps the local corner (1, 1, 1) to the sum of its columns.
  const Matrix4 shortBox = [] {
    Matrix4 m = Matrix4::identity();
    const double v[12] = {0.0851643, 0.289542, 1.31134e-008, 0.328631,  3.72265e-009, 1.26563e-008,
                          -0.3,      0.3,      -0.284951,    0.0865363, 5.73206e-016, 0.374592};
    for (int k = 0; k < 12; ++k) m.m[k / 4][k % 4] = v[k];
    return m;
  }();
  Vec3f corner = shortBox.applyPoint({1, 1, 1});
  bool found = false;
  for (const Vec3f& p : s.shapes[5].positions) found |= length(p - corner) < 1e-6f;
  EXPECT_TRUE(found);
}

TEST(MitsubaLoaderTest, VeachMis) {
  SceneDescription s = loadMitsubaScene(scenePath("veach-mis"));
  EXPECT_EQ(s.shapes.size(), 9u);
  EXPECT_EQ(s.bsdfs.size(), 6u);
  EXPECT_EQ(s.maxDepth, 3);
  EXPECT_EQ(s.camera.width, 1280);
  EXPECT_EQ(s.camera.height, 720);
  EXPECT_FLOAT_EQ(s.camera.fovDegrees, 35.0f);
  struct Expected {
    Vec3f center;
    float radius, radiance;
  };
  const Expected spheres[3] = {
      {{0, 6.5f, -2.8f}, 1.0f, 7.59909f},
      {{0, 6.5f, 0}, 0.5f, 30.3964f},
      {{0, 6.5f, 2.7f}, 0.05f, 3039.64f},
  };
  int found = 0;
  for (const ShapeDescription& shape : s.shapes) {
    if (shape.type != ShapeDescription::Type::Sphere) continue;
    ASSERT_LT(found, 3);
    const Expected& e = spheres[found++];
    expectNear(shape.center, e.center, 1e-6f);
    EXPECT_FLOAT_EQ(shape.radius, e.radius);
    EXPECT_TRUE(shape.isEmitter);
    expectNear(shape.radiance, Vec3f(e.radiance), 0);
    EXPECT_FALSE(shape.flipNormals);
    EXPECT_EQ(s.bsdfs[shape.bsdf].id, "Null");
  }
  EXPECT_EQ(found, 3);
  const BsdfDescription& smooth = s.bsdfs[s.shapes[0].bsdf];
  EXPECT_EQ(smooth.id, "Smooth");
  EXPECT_EQ(smooth.type, BsdfDescription::Type::RoughConductor);
  EXPECT_EQ(smooth.distribution, MicrofacetDistribution::Beckmann);
  EXPECT_FLOAT_EQ(smooth.alpha, 0.01f);
  EXPECT_FLOAT_EQ(smooth.extEta, 1.0f);
  expectNear(smooth.eta, {0.200438f, 0.924033f, 1.10221f}, 0);
  expectNear(smooth.k, {3.91295f, 2.45285f, 2.14219f}, 0);
  expectNear(smooth.specularReflectance, Vec3f(0.3f), 0);
  EXPECT_TRUE(smooth.twoSided);
}

TEST(MitsubaLoaderTest, VeachBidirObjMeshes) {
  SceneDescription s = loadMitsubaScene(scenePath("veach-bidir"));
  ASSERT_EQ(s.shapes.size(), 14u);
  EXPECT_EQ(s.bsdfs.size(), 4u);
  EXPECT_EQ(s.maxDepth, 7);
  int objs = 0, emitters = 0;
  for (const ShapeDescription& shape : s.shapes) {
    EXPECT_EQ(shape.type, ShapeDescription::Type::TriangleMesh);
    EXPECT_GT(shape.indices.size(), 0u);
    EXPECT_EQ(shape.indices.size() % 3, 0u);
    for (uint32_t i : shape.indices) ASSERT_LT(i, shape.positions.size());
    if (shape.faceNormals) {
      EXPECT_TRUE(shape.normals.empty());
    } else {
      EXPECT_EQ(shape.normals.size(), shape.positions.size()) << shape.origin;
    }
    objs += shape.origin.find("(obj models/") != std::string::npos;
    emitters += shape.isEmitter;
  }
  EXPECT_EQ(objs, 12);
  EXPECT_EQ(emitters, 2);
  // Mesh007 (first shape): 128 triangles, faceNormals.
  EXPECT_EQ(s.shapes[0].indices.size(), 3u * 128);
  EXPECT_TRUE(s.shapes[0].faceNormals);
  EXPECT_EQ(s.shapes[0].origin, "scene.xml:51 (obj models/Mesh007.obj)");
  // Mesh002, the glass: 7936 triangles with the file's vertex normals.
  const ShapeDescription& glass = s.shapes[7];
  EXPECT_EQ(glass.indices.size(), 3u * 7936);
  EXPECT_FALSE(glass.faceNormals);
  const BsdfDescription& g = s.bsdfs[glass.bsdf];
  EXPECT_EQ(g.type, BsdfDescription::Type::Dielectric);
  EXPECT_FLOAT_EQ(g.intIOR, 1.5f);
  EXPECT_FLOAT_EQ(g.extIOR, 1.0f);
  EXPECT_FALSE(g.twoSided);
  for (const Vec3f& n : glass.normals) EXPECT_NEAR(length(n), 1.0f, 1e-5f);
}

TEST(MitsubaLoaderTest, WaterCausticObjTransformed) {
  SceneDescription s = loadMitsubaScene(scenePath("water-caustic"));
  ASSERT_EQ(s.shapes.size(), 10u);
  EXPECT_EQ(s.bsdfs.size(), 9u);
  EXPECT_EQ(s.maxDepth, 9);
  const ShapeDescription& surface = s.shapes[8];  // models/Mesh001.obj
  const ShapeDescription& pool = s.shapes[9];     // models/Mesh000.obj, faceNormals
  EXPECT_EQ(surface.indices.size(), 3u * 102938);
  EXPECT_EQ(pool.indices.size(), 3u * 513);
  EXPECT_TRUE(pool.faceNormals);
  EXPECT_FALSE(surface.faceNormals);
  EXPECT_EQ(s.bsdfs[surface.bsdf].type, BsdfDescription::Type::Dielectric);
  EXPECT_FLOAT_EQ(s.bsdfs[surface.bsdf].intIOR, 1.8f);
  // The first vertex of the first face is the file's first "v", scaled by toWorld = diag(1, 1.5,
  // 1).
  std::ifstream obj(kShared + "/scenes/water-caustic/models/Mesh000.obj");
  std::string line;
  while (std::getline(obj, line) && line.rfind("v ", 0) != 0) {
  }
  float x, y, z;
  ASSERT_EQ(sscanf(line.c_str(), "v %f %f %f", &x, &y, &z), 3);
  expectNear(pool.positions[0], {x, 1.5f * y, z}, 1e-6f);
  // The light is tiny and very bright.
  EXPECT_TRUE(s.shapes[7].isEmitter);
  expectNear(s.shapes[7].radiance, {541127, 381972, 127324}, 0);
}

TEST(MitsubaLoaderTest, ObjPathRelativeToXmlNotCwd) {
  TempDir dir;
  dir.write("sub/models/tri.obj",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");  // a quad: 2 triangles
  std::string xml = dir.write("sub/scene.xml", sceneXml(R"(<shape type="obj">
  <string name="filename" value="models/tri.obj"/>
  <transform name="toWorld"><translate x="10"/></transform>
</shape>
)"));
  fs::path old = fs::current_path();
  fs::current_path(dir.path());
  SceneDescription s;
  EXPECT_NO_THROW(s = loadMitsubaScene(xml));
  fs::current_path(old);
  ASSERT_EQ(s.shapes.size(), 1u);
  EXPECT_EQ(s.shapes[0].indices.size(), 6u);
  expectNear(s.shapes[0].positions[0], {10, 0, 0}, 0);
  // No normals in the file and not faceNormals: smooth normals are computed, as Mitsuba does.
  ASSERT_EQ(s.shapes[0].normals.size(), 4u);
  for (const Vec3f& n : s.shapes[0].normals) expectNear(n, {0, 0, 1}, 1e-6f);
  // No bsdf given: a default diffuse 0.5 of its own.
  ASSERT_EQ(s.bsdfs.size(), 1u);
  EXPECT_EQ(s.shapes[0].bsdf, 0);
  expectNear(s.bsdfs[0].reflectance, Vec3f(0.5f), 0);
  EXPECT_EQ(s.bsdfs[0].type, BsdfDescription::Type::Diffuse);
}

// ---- Features of small scenes ----

TEST(MitsubaLoaderTest, TransformOperationsComposeInOrder) {
  TempDir dir;
  std::string xml = dir.write("s.xml", sceneXml(R"(<shape type="rectangle">
  <transform name="toWorld">
    <scale x="2" y="3"/>
    <rotate z="1" angle="90"/>
    <translate x="1"/>
  </transform>
  <boolean name="flipNormals" value="true"/>
</shape>
<shape type="sphere">
  <point name="center" x="1" y="0" z="0"/>
  <float name="radius" value="0.5"/>
  <transform name="toWorld"><scale value="2"/><translate y="1"/></transform>
</shape>
)"));
  SceneDescription s = loadMitsubaScene(xml);
  ASSERT_EQ(s.shapes.size(), 2u);
  // (1, 1, 0) -> scale (2, 3, 0) -> rotate (-3, 2, 0) -> translate (-2, 2, 0).
  const ShapeDescription& r = s.shapes[0];
  bool found = false;
  for (const Vec3f& p : r.positions) found |= length(p - Vec3f(-2, 2, 0)) < 1e-5f;
  EXPECT_TRUE(found);
  for (const Vec3f& n : r.normals) expectNear(n, {0, 0, -1}, 1e-6f);  // flipped
  EXPECT_LT(triangleNormal(r, 0).z, 0);
  EXPECT_EQ(s.shapes[1].type, ShapeDescription::Type::Sphere);
  expectNear(s.shapes[1].center, {2, 1, 0}, 1e-6f);
  EXPECT_FLOAT_EQ(s.shapes[1].radius, 1.0f);
}

TEST(MitsubaLoaderTest, MirroringTransformKeepsOrientation) {
  TempDir dir;
  std::string xml = dir.write("s.xml", sceneXml(R"(<shape type="rectangle">
  <transform name="toWorld"><scale x="-1"/></transform>
</shape>
<shape type="cube"><transform name="toWorld"><scale x="-1"/></transform></shape>
)"));
  SceneDescription s = loadMitsubaScene(xml);
  EXPECT_GT(triangleNormal(s.shapes[0], 0).z, 0);
  expectNear(s.shapes[0].normals[0], {0, 0, 1}, 0);
  for (size_t t = 0; t < 12; ++t) {
    const ShapeDescription& c = s.shapes[1];
    Vec3f centroid = c.positions[c.indices[3 * t]] + c.positions[c.indices[3 * t + 1]] +
                     c.positions[c.indices[3 * t + 2]];
    EXPECT_GT(dot(triangleNormal(c, t), centroid), 0);
  }
}

TEST(MitsubaLoaderTest, ThinlensSensor) {
  TempDir dir;
  auto sensor = [&](const std::string& params) {
    return dir.write("s.xml", sceneXml("<sensor type=\"thinlens\">\n" + params +
                                       "</sensor>\n<shape type=\"rectangle\"/>\n"));
  };
  SceneDescription s = loadMitsubaScene(
      sensor("<float name=\"apertureRadius\" value=\"0.2\"/><float name=\"focusDistance\" "
             "value=\"7\"/>\n"));
  EXPECT_FLOAT_EQ(s.camera.lensRadius, 0.2f);
  EXPECT_FLOAT_EQ(s.camera.focusDistance, 7.0f);
  EXPECT_EQ(loadMitsubaScene(scenePath("cornell-box")).camera.lensRadius, 0);
  EXPECT_NE(loadError(sensor("<float name=\"apertureRadius\" value=\"0.2\"/>\n"))
                .find("needs <float name=\"focusDistance\">"),
            std::string::npos);
  EXPECT_NE(loadError(sensor("<float name=\"apertureRadius\" value=\"-1\"/><float "
                             "name=\"focusDistance\" value=\"7\"/>\n"))
                .find("apertureRadius must be > 0"),
            std::string::npos);
}

// The integrator's strictNormals, as Mitsuba reads it: false when no integrator says it, the
// wrapped integrator's where it says it and the wrapper's otherwise; not a boolean, an error.
TEST(MitsubaLoaderTest, StrictNormalsFromTheIntegrator) {
  TempDir dir;
  auto strict = [&](const std::string& integrator) {
    return loadMitsubaScene(
               dir.write("s.xml", sceneXml(integrator + "<shape type=\"rectangle\"/>\n")))
        .strictNormals;
  };
  EXPECT_FALSE(strict(""));
  EXPECT_FALSE(strict("<integrator type=\"path\"/>\n"));
  EXPECT_TRUE(strict(
      "<integrator type=\"path\"><boolean name=\"strictNormals\" value=\"true\"/></integrator>\n"));
  EXPECT_FALSE(
      strict("<integrator type=\"path\"><boolean name=\"strictNormals\" "
             "value=\"false\"/></integrator>\n"));
  EXPECT_TRUE(
      strict("<integrator type=\"adaptive\"><boolean name=\"strictNormals\" "
             "value=\"true\"/><integrator type=\"path\"/></integrator>\n"));
  EXPECT_FALSE(
      strict("<integrator type=\"adaptive\"><boolean name=\"strictNormals\" "
             "value=\"true\"/><integrator type=\"path\"><boolean "
             "name=\"strictNormals\" value=\"false\"/></integrator></integrator>\n"));
  // With a maxDepth beside it, too (the loader stops at an integrator's maxDepth).
  EXPECT_TRUE(
      strict("<integrator type=\"path\"><integer name=\"maxDepth\" value=\"5\"/><boolean "
             "name=\"strictNormals\" value=\"true\"/></integrator>\n"));
  for (const char* scene : {"cornell-box", "veach-mis", "veach-bidir", "water-caustic"})
    EXPECT_TRUE(loadMitsubaScene(scenePath(scene)).strictNormals) << scene;
  EXPECT_NE(loadError(dir.write("s.xml", sceneXml("<integrator type=\"path\"><boolean "
                                                  "name=\"strictNormals\" value=\"yes\"/>"
                                                  "</integrator>\n<shape type=\"rectangle\"/>\n")))
                .find("'strictNormals': 'yes' is not a boolean"),
            std::string::npos);
}

TEST(MitsubaLoaderTest, SensorOptionsAndBsdfVariants) {
  TempDir dir;
  std::string xml = dir.write("s.xml", sceneXml(R"(<integrator type="path"/>
<sensor type="perspective">
  <float name="fov" value="40"/>
  <string name="fovAxis" value="smaller"/>
  <transform name="toWorld"><lookat origin="0, 0, 5" target="0 0 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="32"/>
    <rfilter type="box"/></film>
</sensor>
<bsdf type="dielectric" id="w"><string name="intIOR" value="water"/></bsdf>
<bsdf type="roughconductor" id="c">
  <string name="distribution" value="ggx"/>
  <float name="alphaU" value="0.00001"/><float name="alphaV" value="0.00001"/>
</bsdf>
<bsdf type="twosided" id="t"><ref id="c"/></bsdf>
<bsdf type="diffuse" id="d"><spectrum name="reflectance" value="0.25"/></bsdf>
<bsdf type="diffuse" id="e"><float name="reflectance" value="0.75"/></bsdf>
<bsdf type="diffuse" id="f"><rgb name="reflectance" value="0.1 0.2 0.3"/></bsdf>
<bsdf type="conductor" id="m">
  <string name="material" value="none"/><rgb name="specularReflectance" value="0.5 0.6 0.7"/>
</bsdf>
<bsdf type="conductor" id="n"><rgb name="eta" value="0.2 0.9 1.1"/><rgb name="k" value="3.9 2.4 2.1"/>
  <float name="extEta" value="1.33"/></bsdf>
<bsdf type="roughdielectric" id="r">
  <float name="alpha" value="0.3"/><float name="intIOR" value="1.7"/>
  <boolean name="sampleVisible" value="true"/>
</bsdf>
)"));
  SceneDescription s = loadMitsubaScene(xml);
  EXPECT_EQ(s.maxDepth, -1);
  EXPECT_EQ(s.camera.fovAxis, FovAxis::Smaller);
  EXPECT_EQ(s.camera.width, 64);
  EXPECT_EQ(s.camera.height, 32);
  EXPECT_EQ(s.camera.filter, FilterType::Box);
  expectNear(s.camera.toWorld.applyVector({0, 0, 1}), {0, 0, -1}, 1e-6f);
  expectNear(s.camera.toWorld.applyPoint({0, 0, 0}), {0, 0, 5}, 0);
  ASSERT_EQ(s.bsdfs.size(), 9u);
  EXPECT_FLOAT_EQ(s.bsdfs[0].intIOR, 1.333f);
  EXPECT_FLOAT_EQ(s.bsdfs[0].extIOR, 1.000277f);
  EXPECT_EQ(s.bsdfs[1].distribution, MicrofacetDistribution::GGX);
  EXPECT_FLOAT_EQ(s.bsdfs[1].alpha, 1e-4f);                         // clamped up
  expectNear(s.bsdfs[1].eta, {0.200438f, 0.924033f, 1.10221f}, 0);  // copper by default
  EXPECT_TRUE(s.bsdfs[2].twoSided);
  EXPECT_EQ(s.bsdfs[2].type, BsdfDescription::Type::RoughConductor);
  EXPECT_EQ(s.bsdfs[2].id, "t");
  expectNear(s.bsdfs[3].reflectance, Vec3f(0.25f), 0);
  expectNear(s.bsdfs[4].reflectance, Vec3f(0.75f), 0);
  expectNear(s.bsdfs[5].reflectance, {0.1f, 0.2f, 0.3f}, 0);
  EXPECT_EQ(s.bsdfs[6].type, BsdfDescription::Type::Conductor);
  expectNear(s.bsdfs[6].eta, Vec3f(0.0f), 0);  // "none": a perfect mirror
  expectNear(s.bsdfs[6].k, Vec3f(1.0f), 0);
  expectNear(s.bsdfs[6].specularReflectance, {0.5f, 0.6f, 0.7f}, 0);
  EXPECT_EQ(s.bsdfs[7].type, BsdfDescription::Type::Conductor);
  expectNear(s.bsdfs[7].k, {3.9f, 2.4f, 2.1f}, 0);
  EXPECT_FLOAT_EQ(s.bsdfs[7].extEta, 1.33f);
  EXPECT_EQ(s.bsdfs[8].type, BsdfDescription::Type::RoughDielectric);
  EXPECT_EQ(s.bsdfs[8].distribution, MicrofacetDistribution::Beckmann);  // Mitsuba's default
  EXPECT_FLOAT_EQ(s.bsdfs[8].alpha, 0.3f);
  EXPECT_FLOAT_EQ(s.bsdfs[8].intIOR, 1.7f);
  EXPECT_FLOAT_EQ(s.bsdfs[8].extIOR, 1.000277f);
}

// plastic and roughplastic: the coated diffuse, with Mitsuba's defaults (polypropylene, air, a
// white specular reflectance, the linear form), the smooth one's coat of alpha 1e-4 said in a
// warning, a textured base, and the errors of the model.
TEST(MitsubaLoaderTest, PlasticsAreCoatedDiffuse) {
  TempDir dir;
  SceneDescription s = loadMitsubaScene(dir.write("s.xml", sceneXml(R"(
<bsdf type="plastic" id="p"/>
<bsdf type="roughplastic" id="r">
  <string name="distribution" value="ggx"/><float name="alpha" value="0.2"/>
  <float name="intIOR" value="1.6"/><rgb name="diffuseReflectance" value="0.1 0.2 0.3"/>
  <spectrum name="specularReflectance" value="0.5"/><boolean name="nonlinear" value="true"/>
</bsdf>
<bsdf type="twosided" id="t"><ref id="r"/></bsdf>
)")));
  ASSERT_EQ(s.bsdfs.size(), 3u);
  const BsdfDescription &p = s.bsdfs[0], &r = s.bsdfs[1];
  EXPECT_EQ(p.type, BsdfDescription::Type::CoatedDiffuse);
  EXPECT_FLOAT_EQ(p.alpha, 1e-4f);
  EXPECT_FLOAT_EQ(p.intIOR, 1.49f);
  EXPECT_FLOAT_EQ(p.extIOR, 1.000277f);
  expectNear(p.reflectance, Vec3f(0.5f), 0);
  expectNear(p.specularReflectance, Vec3f(1.0f), 0);
  EXPECT_FALSE(p.nonlinear);
  ASSERT_TRUE(p.coating);
  EXPECT_EQ(r.type, BsdfDescription::Type::CoatedDiffuse);
  EXPECT_EQ(r.distribution, MicrofacetDistribution::GGX);
  EXPECT_FLOAT_EQ(r.alpha, 0.2f);
  EXPECT_FLOAT_EQ(r.intIOR, 1.6f);
  expectNear(r.reflectance, {0.1f, 0.2f, 0.3f}, 0);
  expectNear(r.specularReflectance, Vec3f(0.5f), 0);
  EXPECT_TRUE(r.nonlinear);
  ASSERT_TRUE(r.coating);
  EXPECT_TRUE(s.bsdfs[2].twoSided);
  EXPECT_EQ(s.bsdfs[2].coating, r.coating);  // one table for one kind of coat
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("roughness 1e-4"), std::string::npos) << s.warnings[0];

  const struct {
    std::string xml, message;
  } bad[] = {
      {R"(<bsdf type="plastic"><float name="intIOR" value="1.5"/><float name="extIOR" value="1.5"/></bsdf>)",
       "intIOR and extIOR must differ"},
      {R"(<bsdf type="roughplastic"><rgb name="diffuseReflectance" value="1.2 0.5 0.5"/></bsdf>)",
       "a reflectance above 1"},
      {R"(<bsdf type="roughplastic"><string name="distribution" value="phong"/></bsdf>)",
       "unsupported microfacet distribution 'phong'"},
      {R"(<bsdf type="plastic"><float name="fdrInt" value="0.5"/></bsdf>)",
       "unsupported parameter 'fdrInt'"},
  };
  for (const auto& c : bad)
    expectLoadError(dir.write("bad.xml", "<scene version=\"0.5.0\">\n" + c.xml + "\n</scene>"),
                    c.message, 2);
}

// A PLY (ASCII, quads, per-vertex normals) loads as the OBJ of the same mesh: the same triangles
// in world space (the quads split by Open Asset Import Library, corners in the file's winding),
// normals transformed and normalized, flipNormals and faceNormals as for OBJ.
TEST(MitsubaLoaderTest, PlyMeshEqualsTheObj) {
  TempDir dir;
  dir.write("quads.ply", R"(ply
format ascii 1.0
comment a unit square with leaning normals and a tilted one
element vertex 8
property float x
property float y
property float z
property float nx
property float ny
property float nz
element face 2
property list uchar int vertex_indices
end_header
0 0 0 0.3 0 1
1 0 0 0.3 0 1
1 1 0 0.3 0 1
0 1 0 0.3 0 1
0 0 1 0 -1 1
1 0 1 0 -1 1
1 1 2 0 -1 1
0 1 2 0 -1 1
4 0 1 2 3
4 4 5 6 7
)");
  dir.write("quads.obj",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 2\nv 0 1 2\n"
            "vn 0.2873479 0 0.9578263\nvn 0 -0.7071068 0.7071068\n"
            "f 1//1 2//1 3//1 4//1\nf 5//2 6//2 7//2 8//2\n");
  const std::string shape = R"(
  <transform name="toWorld"><scale x="2"/><translate y="3"/></transform>
</shape>
)";
  SceneDescription s = loadMitsubaScene(dir.write(
      "s.xml",
      sceneXml("<shape type=\"ply\"><string name=\"filename\" value=\"quads.ply\"/>" + shape +
               "<shape type=\"obj\"><string name=\"filename\" value=\"quads.obj\"/>" + shape +
               "<shape type=\"ply\"><string name=\"filename\" value=\"quads.ply\"/>"
               "<boolean name=\"flipNormals\" value=\"true\"/>"
               "<boolean name=\"faceNormals\" value=\"true\"/></shape>\n")));
  ASSERT_EQ(s.shapes.size(), 3u);
  const ShapeDescription &ply = s.shapes[0], &obj = s.shapes[1], &flipped = s.shapes[2];
  ASSERT_EQ(ply.indices.size(), 12u);
  ASSERT_EQ(obj.indices.size(), 12u);
  EXPECT_EQ(ply.origin, "s.xml:3 (ply quads.ply)");
  // The same corners (world-space positions with their normals) and the same surface: the
  // quads may be split along either diagonal, so the triangles are compared by their total
  // vector area, which is the same for both splits of a planar quad.
  auto corners = [](const ShapeDescription& m) {
    std::vector<std::array<float, 6>> c;
    for (uint32_t i : m.indices) {
      const Vec3f &p = m.positions[i], &n = m.normals[i];
      c.push_back({p.x, p.y, p.z, n.x, n.y, n.z});
    }
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
    return c;
  };
  const auto a = corners(ply), b = corners(obj);
  ASSERT_EQ(a.size(), 8u);
  ASSERT_EQ(b.size(), 8u);
  for (size_t v = 0; v < 8; ++v) {
    for (int c = 0; c < 6; ++c) EXPECT_NEAR(a[v][c], b[v][c], 1e-6f) << v;
  }
  Vec3f areaPly(0.0f), areaObj(0.0f);
  for (size_t t = 0; t < 4; ++t)
    areaPly += triangleNormal(ply, t), areaObj += triangleNormal(obj, t);
  expectNear(areaPly, areaObj, 1e-5f);
  // Twice the vector areas, x scaled by 2: the flat square (0, 0, 2), the tilted one (0, -2, 2).
  expectNear(areaPly, 2 * (Vec3f(0, 0, 2) + Vec3f(0, -2, 2)), 1e-5f);
  // The first square, scaled by 2 in x and moved up 3: its normal stays +z; the tilted one's
  // (0, -1, 1) / sqrt(2) is transformed by the inverse transpose (x scale: unchanged here).
  for (size_t i = 0; i < ply.positions.size(); ++i) {
    EXPECT_NEAR(length(ply.normals[i]), 1.0f, 1e-6f);
    EXPECT_GE(ply.positions[i].y, 3.0f);
  }
  // flipNormals reverses the winding; faceNormals drops the vertex normals.
  EXPECT_TRUE(flipped.faceNormals);
  EXPECT_TRUE(flipped.normals.empty());
  for (size_t t = 0; t < 4; ++t) {
    Vec3f n = normalize(triangleNormal(flipped, t));
    EXPECT_TRUE(n.z < 0) << t;
  }
}

// ---- Errors ----

TEST(MitsubaLoaderErrorTest, MissingFile) {
  std::string msg = loadError("/nonexistent/dir/scene.xml");
  EXPECT_NE(msg.find("/nonexistent/dir/scene.xml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not found"), std::string::npos) << msg;
}

TEST(MitsubaLoaderErrorTest, MalformedXmlNamesFileAndLine) {
  TempDir dir;
  std::string xml = dir.write("bad.xml", sceneXml(R"(<shape type="rectangle">
  <float name=radius value="1"/>
</shape>
)"));
  std::string msg = loadError(xml);
  EXPECT_EQ(msg.rfind(xml + ":4: malformed XML", 0), 0u) << msg;

  std::string unclosed = dir.write("unclosed.xml",
                                   "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n"
                                   "  <shape type=\"cube\">\n");
  msg = loadError(unclosed);
  EXPECT_NE(msg.find("unclosed.xml:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("malformed XML"), std::string::npos) << msg;
}

TEST(MitsubaLoaderErrorTest, MissingMeshNamesObjAndLine) {
  TempDir dir;
  std::string xml = dir.write("s.xml", sceneXml(R"(<shape type="obj">
  <string name="filename" value="models/nothere.obj"/>
</shape>
)"));
  std::string msg = loadError(xml);
  EXPECT_EQ(msg.rfind(xml + ":4:", 0), 0u) << msg;
  EXPECT_NE(msg.find("models/nothere.obj"), std::string::npos) << msg;
}

TEST(MitsubaLoaderErrorTest, UnparseableOrEmptyObj) {
  TempDir dir;
  dir.write("empty.obj", "# nothing\nv 0 0 0\n");
  dir.write("badindex.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  std::string msg = loadError(dir.write(
      "a.xml",
      sceneXml("<shape type=\"obj\"><string name=\"filename\" value=\"empty.obj\"/></shape>\n")));
  EXPECT_NE(msg.find(":3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("no triangles"), std::string::npos) << msg;
  msg = loadError(dir.write(
      "b.xml",
      sceneXml(
          "<shape type=\"obj\"><string name=\"filename\" value=\"badindex.obj\"/></shape>\n")));
  EXPECT_NE(msg.find("badindex.obj"), std::string::npos) << msg;
}

TEST(MitsubaLoaderErrorTest, UnknownTypesNameTypeAndLine) {
  TempDir dir;
  std::string msg = loadError(dir.write("a.xml", sceneXml(R"(<bsdf type="fancyplastic" id="x">
</bsdf>
)")));
  EXPECT_EQ(msg.rfind(dir.path().string() + "/a.xml:3:", 0), 0u) << msg;
  EXPECT_NE(msg.find("fancyplastic"), std::string::npos) << msg;

  msg = loadError(dir.write("b.xml", sceneXml("\n<shape type=\"cylinder\"/>\n")));
  EXPECT_NE(msg.find("b.xml:4:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cylinder"), std::string::npos) << msg;

  msg = loadError(dir.write("c.xml", sceneXml("<emitter type=\"envmap\"/>\n")));
  EXPECT_NE(msg.find("c.xml:3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("envmap"), std::string::npos) << msg;

  msg = loadError(dir.write("d.xml", sceneXml("<sensor type=\"thinlens\"/>\n")));
  EXPECT_NE(msg.find("thinlens"), std::string::npos) << msg;

  msg = loadError(dir.write(
      "e.xml",
      sceneXml("<sensor type=\"perspective\"><film type=\"hdrfilm\">\n<rfilter type=\"mitchell\"/>"
               "</film></sensor>\n")));
  EXPECT_NE(msg.find("e.xml:4:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("mitchell"), std::string::npos) << msg;

  msg = loadError(dir.write("f.xml", sceneXml("<shape type=\"cube\">\n<texture type=\"bitmap\"/>"
                                              "</shape>\n")));
  EXPECT_NE(msg.find("f.xml:4:"), std::string::npos) << msg;

  msg = loadError(dir.write("g.xml", sceneXml("<blob/>\n")));
  EXPECT_NE(msg.find("g.xml:3: unknown element <blob>"), std::string::npos) << msg;

  msg = loadError(dir.write("h.xml", sceneXml("<bsdf type=\"roughconductor\"><string "
                                              "name=\"distribution\" value=\"phong\"/></bsdf>\n")));
  EXPECT_NE(msg.find("phong"), std::string::npos) << msg;

  msg = loadError(dir.write(
      "i.xml",
      sceneXml("<bsdf type=\"diffuse\">\n<float name=\"roughness\" value=\"0.1\"/></bsdf>\n")));
  EXPECT_NE(msg.find("i.xml:4:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("roughness"), std::string::npos) << msg;
}

// PLY files that cannot be read: missing (file and line of the shape), not PLY, truncated
// binary, points only; each a clear error naming the file, nothing loaded.
TEST(MitsubaLoaderErrorTest, BadPlyFiles) {
  TempDir dir;
  dir.write("garbage.ply", "this is not a mesh\n");
  dir.write("truncated.ply",
            "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
            "property float y\nproperty float z\nelement face 1\n"
            "property list uchar int vertex_indices\nend_header\n\x01\x02");
  dir.write("points.ply",
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n0 0 0\n1 1 1\n");
  dir.write("badindex.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
            "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n");
  // A count no file of this size can hold: refused before assimp allocates for it.
  dir.write("absurd.ply",
            "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
            "end_header\n0000");
  auto load = [&](const std::string& file) {
    return loadError(dir.write(
        file + ".xml", sceneXml("<shape type=\"ply\">\n<string name=\"filename\" value=\"" + file +
                                "\"/></shape>\n")));
  };
  std::string msg = load("nothere.ply");
  EXPECT_NE(msg.find("nothere.ply.xml:4: mesh file 'nothere.ply' not found"), std::string::npos)
      << msg;
  // Only PLY reaches assimp: an OBJ, whatever its name, is not read by another importer (some
  // open further files that the first one names).
  dir.write("obj-inside.ply", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  for (const char* file : {"obj-inside.ply", "tri.obj"}) {
    msg = load(file);
    EXPECT_NE(msg.find(std::string(":4: cannot read PLY '") + file +
                       "': not a PLY file (it does not start with the line 'ply')"),
              std::string::npos)
        << msg;
  }
  msg = load("absurd.ply");
  EXPECT_NE(msg.find("cannot read PLY 'absurd.ply': the header declares elements that need at "
                     "least 16000000000 bytes but only 4 follow it"),
            std::string::npos)
      << msg;
  for (const char* file : {"garbage.ply", "truncated.ply", "points.ply", "badindex.ply"}) {
    msg = load(file);
    EXPECT_NE(msg.find(std::string(":4: cannot read PLY '") + file + "': "), std::string::npos)
        << msg;
  }
  msg = loadError(dir.write("noname.xml", sceneXml("<shape type=\"ply\"/>\n")));
  EXPECT_NE(msg.find("noname.xml:3: ply shape without a filename parameter"), std::string::npos)
      << msg;
  msg = loadError(dir.write(
      "unknown.xml", sceneXml("<shape type=\"ply\"><string name=\"filename\" value=\"x.ply\"/>\n"
                              "<float name=\"maxSmoothAngle\" value=\"30\"/></shape>\n")));
  EXPECT_NE(msg.find("maxSmoothAngle"), std::string::npos) << msg;
}

// Meshes outside the scene's folder are refused, however named: a farm submission uploads the
// folder only, and a coordinator must not read its own files for a client. A path that climbs
// out and back in is inside.
TEST(MitsubaLoaderErrorTest, MeshesOutsideTheSceneFolderAreRefused) {
  TempDir dir;
  const std::string triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  dir.write("outside.obj", triangle);
  dir.write("scene/models/inside.obj", triangle);
  auto load = [&](const std::string& filename) {
    return loadError(dir.write("scene/s.xml",
                               sceneXml("<shape type=\"obj\">\n<string name=\"filename\" value=\"" +
                                        filename + "\"/></shape>\n")));
  };
  for (const std::string& outside :
       {std::string("../outside.obj"), std::string("models/../../outside.obj"),
        (dir.path() / "outside.obj").string(), (dir.path() / "scene/models/inside.obj").string()}) {
    const std::string msg = load(outside);
    EXPECT_NE(msg.find("s.xml:4: mesh file '" + outside + "' is outside the scene's folder"),
              std::string::npos)
        << msg;
  }
  EXPECT_EQ(load("models/../models/inside.obj"), "");
  EXPECT_EQ(load("./models/inside.obj"), "");
}

// A dielectric has two sides by nature (inside and outside differ by the relative index);
// twosided would mirror the back side onto the front and swap reflection and transmission with
// the wrong index. Mitsuba refuses the combination; so do we, with or without a <ref>.
TEST(MitsubaLoaderErrorTest, TwosidedDielectricIsRefused) {
  TempDir dir;
  std::string msg = loadError(dir.write(
      "a.xml", sceneXml("<bsdf type=\"twosided\">\n<bsdf type=\"dielectric\"/></bsdf>\n")));
  EXPECT_NE(msg.find("a.xml:3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("dielectric"), std::string::npos) << msg;
  msg = loadError(
      dir.write("b.xml", sceneXml("<bsdf type=\"dielectric\" id=\"glass\"/>\n"
                                  "<bsdf type=\"twosided\">\n<ref id=\"glass\"/></bsdf>\n")));
  EXPECT_NE(msg.find("b.xml:4:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("dielectric"), std::string::npos) << msg;
  msg = loadError(dir.write(
      "c.xml", sceneXml("<bsdf type=\"twosided\">\n<bsdf type=\"roughdielectric\"/></bsdf>\n")));
  EXPECT_NE(msg.find("c.xml:3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("twosided cannot wrap a dielectric"), std::string::npos) << msg;
  // Equal indices: a rough interface that refracts nothing (its transmission lobe is singular).
  msg = loadError(dir.write("e.xml", sceneXml("<bsdf type=\"roughdielectric\">\n<float "
                                              "name=\"intIOR\" value=\"1.3\"/><float "
                                              "name=\"extIOR\" value=\"1.3\"/></bsdf>\n")));
  EXPECT_NE(msg.find("e.xml:3: roughdielectric with intIOR equal to extIOR does not refract"),
            std::string::npos)
      << msg;
  // Tinted glass has no slot: refused, rough or smooth.
  msg = loadError(dir.write("d.xml", sceneXml("<bsdf type=\"roughdielectric\">\n<rgb "
                                              "name=\"specularTransmittance\" value=\"0.5 1 1\"/>"
                                              "</bsdf>\n")));
  EXPECT_NE(msg.find("d.xml:4: specularTransmittance other than 1 is not supported for "
                     "roughdielectric"),
            std::string::npos)
      << msg;
}

TEST(MitsubaLoaderErrorTest, NonFiniteAndNonNumericParameters) {
  TempDir dir;
  struct Case {
    std::string body, expected;
  };
  const Case cases[] = {
      {"<sensor type=\"perspective\">\n<float name=\"fov\" value=\"nan\"/></sensor>\n", "nan"},
      {"<sensor type=\"perspective\">\n<float name=\"fov\" value=\"inf\"/></sensor>\n", "inf"},
      {"<sensor type=\"perspective\">\n<float name=\"fov\" value=\"abc\"/></sensor>\n", "abc"},
      {"<sensor type=\"perspective\">\n<float name=\"fov\" value=\"1.5x\"/></sensor>\n", "1.5x"},
      {"<bsdf type=\"diffuse\">\n<rgb name=\"reflectance\" value=\"nan, 0, 0\"/></bsdf>\n", "nan"},
      {"<bsdf type=\"diffuse\">\n<rgb name=\"reflectance\" value=\"1e39\"/></bsdf>\n", "1e39"},
      {"<bsdf type=\"diffuse\">\n<rgb name=\"reflectance\" value=\"0.1, 0.2\"/></bsdf>\n",
       "reflectance"},
      {"<bsdf type=\"dielectric\">\n<float name=\"intIOR\" value=\"-1\"/></bsdf>\n", "intIOR"},
      {"<bsdf type=\"dielectric\">\n<string name=\"intIOR\" value=\"unobtainium\"/></bsdf>\n",
       "unobtainium"},
      {"<bsdf type=\"roughconductor\">\n<float name=\"alpha\" value=\"0\"/></bsdf>\n", "alpha"},
      {"<bsdf type=\"roughconductor\">\n<float name=\"alpha\" value=\"-0.1\"/></bsdf>\n", "alpha"},
      {"<shape type=\"sphere\">\n<float name=\"radius\" value=\"-1\"/></shape>\n", "radius"},
      {"<shape type=\"sphere\">\n<float name=\"radius\" value=\"0\"/></shape>\n", "radius"},
      {"<shape type=\"sphere\">\n<point name=\"center\" x=\"nan\"/></shape>\n", "nan"},
      {"<sensor type=\"perspective\">\n<float name=\"fov\" value=\"180\"/></sensor>\n", "fov"},
      {"<sensor type=\"perspective\">\n<float name=\"fov\" value=\"0\"/></sensor>\n", "fov"},
      {"<sensor type=\"perspective\">\n<string name=\"fovAxis\" value=\"z\"/></sensor>\n",
       "fovAxis"},
      {"<shape type=\"cube\"><transform name=\"toWorld\">\n<matrix value=\"1 0 0 0 0 1 0 0 0 0 "
       "1 0 0 0 0\"/></transform></shape>\n",
       "16 numbers"},
      {"<shape type=\"cube\">\n<transform name=\"toWorld\"><matrix value=\"1 0 0 0 0 0 0 0 0 0 "
       "1 0 0 0 0 1\"/></transform></shape>\n",
       "singular"},
      {"<shape type=\"cube\">\n<transform name=\"toWorld\"><scale x=\"0\"/></transform></shape>\n",
       "singular"},
      {"<shape type=\"sphere\">\n<transform name=\"toWorld\"><scale "
       "x=\"2\"/></transform></shape>\n",
       "non-uniform"},
      {"<shape type=\"cube\"><emitter type=\"area\">\n<rgb name=\"radiance\" value=\"1, -1, 1\"/>"
       "</emitter></shape>\n",
       "negative"},
      {"<integrator type=\"path\">\n<integer name=\"maxDepth\" value=\"2.5\"/></integrator>\n",
       "maxDepth"},
      {"<shape type=\"obj\"><string name=\"filename\" value=\"a.obj\"/>\n"
       "<boolean name=\"faceNormals\" value=\"maybe\"/></shape>\n",
       "maybe"},
  };
  for (const Case& c : cases) {
    std::string path = dir.write("p.xml", sceneXml(c.body));
    std::string msg = loadError(path);
    EXPECT_EQ(msg.rfind(path + ":4: ", 0), 0u) << c.body << " -> " << msg;
    EXPECT_NE(msg.find(c.expected), std::string::npos) << c.body << " -> " << msg;
  }
}

TEST(MitsubaLoaderErrorTest, References) {
  TempDir dir;
  std::string msg = loadError(dir.write("a.xml", sceneXml(R"(<shape type="cube">
  <ref id="NoSuchBsdf"/>
</shape>
)")));
  EXPECT_NE(msg.find("a.xml:4:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("NoSuchBsdf"), std::string::npos) << msg;

  msg = loadError(dir.write("b.xml", sceneXml(R"(<shape type="cube" id="box"/>
<shape type="cube">
  <ref id="box"/>
</shape>
)")));
  EXPECT_NE(msg.find("b.xml:5:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("box"), std::string::npos) << msg;
  EXPECT_NE(msg.find("<shape>"), std::string::npos) << msg;

  msg = loadError(dir.write("c.xml", sceneXml(R"(<shape type="cube"><ref id="later"/></shape>
<bsdf type="diffuse" id="later"/>
)")));
  EXPECT_NE(msg.find("c.xml:3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 4"), std::string::npos) << msg;

  msg = loadError(dir.write("d.xml", sceneXml(R"(<bsdf type="diffuse" id="x"/>
<bsdf type="diffuse" id="x"/>
)")));
  EXPECT_NE(msg.find("d.xml:4: duplicate id 'x'"), std::string::npos) << msg;

  msg = loadError(
      dir.write("e.xml", sceneXml(R"(<bsdf type="twosided"><bsdf type="diffuse" id="in"/></bsdf>
<shape type="cube"><ref id="in"/></shape>
)")));
  EXPECT_NE(msg.find("e.xml:4:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 3"), std::string::npos) << msg;
}

TEST(MitsubaLoaderErrorTest, DeepNestingIsRefused) {
  TempDir dir;
  std::string body;
  for (int i = 0; i < 200; ++i) body += "<bsdf type=\"twosided\">";
  body += "<bsdf type=\"diffuse\"/>";
  for (int i = 0; i < 200; ++i) body += "</bsdf>";
  std::string msg = loadError(dir.write("deep.xml", sceneXml(body + "\n")));
  EXPECT_NE(msg.find("nested too deeply"), std::string::npos) << msg;
  // A few levels are fine.
  std::string path = dir.write(
      "ok.xml",
      sceneXml("<bsdf type=\"twosided\" id=\"a\"><bsdf type=\"twosided\"><bsdf type=\"diffuse\"/>"
               "</bsdf></bsdf>\n"));
  EXPECT_EQ(loadError(path), "");
}

TEST(MitsubaLoaderErrorTest, AbsurdFilmResolution) {
  TempDir dir;
  for (const char* film :
       {"<integer name=\"width\" value=\"100000\"/>", "<integer name=\"height\" value=\"0\"/>",
        "<integer name=\"width\" value=\"-5\"/>",
        "<integer name=\"width\" value=\"40000\"/><integer name=\"height\" value=\"40000\"/>",
        "<integer name=\"width\" value=\"99999999999999999999\"/>"}) {
    std::string path = dir.write("f.xml", sceneXml(std::string("<sensor type=\"perspective\">\n"
                                                               "<film type=\"hdrfilm\">") +
                                                   film + "</film></sensor>\n"));
    std::string msg = loadError(path);
    EXPECT_EQ(msg.rfind(path + ":4: ", 0), 0u) << film << " -> " << msg;
  }
}

TEST(MitsubaLoaderErrorTest, VersionAndRoot) {
  TempDir dir;
  EXPECT_NE(loadError(dir.write("a.xml", "<scene version=\"3.0.0\"/>")).find("a.xml:1:"),
            std::string::npos);
  EXPECT_NE(loadError(dir.write("b.xml", "<notscene version=\"0.5.0\"/>")).find("<scene>"),
            std::string::npos);
}

// ---- Film override ----

SceneDescription sceneWithFilm(int w, int h, float fov, FovAxis axis) {
  SceneDescription s;
  s.camera.width = w;
  s.camera.height = h;
  s.camera.fovDegrees = fov;
  s.camera.fovAxis = axis;
  return s;
}

double degrees(double radians) {
  return radians * 180.0 / 3.14159265358979323846;
}
double halfTan(double deg) {
  return std::tan(0.5 * deg * 3.14159265358979323846 / 180.0);
}

TEST(FilmOverrideTest, OneSideFollowsAspect) {
  SceneDescription s = sceneWithFilm(1280, 720, 35, FovAxis::X);
  applyFilmOverride(s, 320, 0);
  EXPECT_EQ(s.camera.width, 320);
  EXPECT_EQ(s.camera.height, 180);
  EXPECT_FLOAT_EQ(s.camera.fovDegrees, 35);
  s = sceneWithFilm(1024, 1024, 19.5f, FovAxis::X);
  applyFilmOverride(s, 0, 256);
  EXPECT_EQ(s.camera.width, 256);
  EXPECT_EQ(s.camera.height, 256);
  s = sceneWithFilm(1000, 3, 30, FovAxis::X);
  applyFilmOverride(s, 100, 0);
  EXPECT_EQ(s.camera.height, 1);  // rounded, at least 1
  s = sceneWithFilm(640, 480, 30, FovAxis::Y);
  applyFilmOverride(s, 0, 0);
  EXPECT_EQ(s.camera.width, 640);
  EXPECT_EQ(s.camera.fovAxis, FovAxis::Y);
  applyFilmOverride(s, 320, 240);  // same aspect: nothing to convert
  EXPECT_EQ(s.camera.fovAxis, FovAxis::Y);
  EXPECT_FLOAT_EQ(s.camera.fovDegrees, 30);
}

TEST(FilmOverrideTest, KeepsHorizontalExtent) {
  // fovAxis y on a 2:1 film: horizontal half-extent = 2 tan(15 deg).
  SceneDescription s = sceneWithFilm(100, 50, 30, FovAxis::Y);
  applyFilmOverride(s, 100, 100);
  EXPECT_EQ(s.camera.fovAxis, FovAxis::X);
  EXPECT_NEAR(s.camera.fovDegrees, 2 * degrees(std::atan(2 * halfTan(30))), 1e-4);
  // "smaller" on a 2:1 film is y.
  s = sceneWithFilm(200, 100, 30, FovAxis::Smaller);
  applyFilmOverride(s, 50, 100);
  EXPECT_NEAR(s.camera.fovDegrees, 2 * degrees(std::atan(2 * halfTan(30))), 1e-4);
  // "larger" on a 2:1 film is x already.
  s = sceneWithFilm(200, 100, 30, FovAxis::Larger);
  applyFilmOverride(s, 100, 100);
  EXPECT_NEAR(s.camera.fovDegrees, 30, 1e-5);
  EXPECT_EQ(s.camera.fovAxis, FovAxis::X);
  // Diagonal on 300x400: x half-extent = diagonal half-extent * 300 / 500.
  s = sceneWithFilm(300, 400, 50, FovAxis::Diagonal);
  applyFilmOverride(s, 400, 400);
  EXPECT_NEAR(s.camera.fovDegrees, 2 * degrees(std::atan(0.6 * halfTan(50))), 1e-4);
  EXPECT_EQ(s.camera.width, 400);
}

TEST(FilmOverrideTest, RejectsBadSizes) {
  SceneDescription s = sceneWithFilm(64, 64, 30, FovAxis::X);
  EXPECT_THROW(applyFilmOverride(s, -1, 0), std::invalid_argument);
  EXPECT_THROW(applyFilmOverride(s, 70000, 0), std::invalid_argument);
  EXPECT_THROW(applyFilmOverride(s, 30000, 30000), std::invalid_argument);
  EXPECT_EQ(s.camera.width, 64);  // unchanged after a refusal
}

}  // namespace
}  // namespace farm
