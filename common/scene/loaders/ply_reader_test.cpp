#include "common/scene/loaders/ply_reader.h"

#include <gtest/gtest.h>

namespace farm {
namespace {

// Twice the vector area of triangle t.
Vec3f doubleArea(const std::vector<Vec3f>& p, const std::vector<uint32_t>& tri, size_t t) {
  const Vec3f &a = p[tri[3 * t]], &b = p[tri[3 * t + 1]], &c = p[tri[3 * t + 2]];
  return cross(b - a, c - a);
}

// A polygon is split well when it gives n - 2 triangles that all face the polygon's way and
// whose areas add up to its own: a triangle that overlaps another or leaves the polygon (what a
// fan from the wrong corner of a concave polygon makes) faces backwards or adds area.
void expectCleanSplit(const std::vector<Vec3f>& p, const std::vector<uint32_t>& polygon,
                      const Vec3f& normal, float area) {
  std::vector<uint32_t> tri;
  triangulatePolygon(p, polygon, tri);
  ASSERT_EQ(tri.size(), 3 * (polygon.size() - 2));
  float sum = 0;
  for (size_t t = 0; t < tri.size() / 3; ++t) {
    const Vec3f a = doubleArea(p, tri, t);
    EXPECT_GT(dot(a, normal), 0) << "triangle " << t << " faces away from the polygon";
    sum += 0.5f * length(a);
  }
  EXPECT_NEAR(sum, area, 1e-5f * area);
}

TEST(PlyTriangulation, ConcaveQuadSplitsThroughItsReflexCorner) {
  // A dart in the z = 0 plane, area 4, whose reflex corner (1, 1) comes second: a fan from the
  // first corner would cut along the outside diagonal.
  const std::vector<Vec3f> p = {{4, 0, 0}, {1, 1, 0}, {0, 4, 0}, {0, 0, 0}};
  expectCleanSplit(p, {0, 1, 2, 3}, {0, 0, 1}, 4.0f);
  // Every rotation of the corners, and the reverse winding (which faces -z).
  for (uint32_t r = 1; r < 4; ++r)
    expectCleanSplit(p, {r, (r + 1) % 4, (r + 2) % 4, (r + 3) % 4}, {0, 0, 1}, 4.0f);
  expectCleanSplit(p, {3, 2, 1, 0}, {0, 0, -1}, 4.0f);
}

TEST(PlyTriangulation, ConcaveHexagonInATiltedPlane) {
  // An L of area 3 (three unit squares) in the plane spanned by u and v.
  const Vec3f u = normalize(Vec3f(1, 1, 0)), v = normalize(Vec3f(-1, 1, 2));
  const float l[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  std::vector<Vec3f> p;
  for (const auto& c : l) p.push_back(Vec3f(5, -1, 2) + c[0] * u + c[1] * v);
  for (uint32_t r = 0; r < 6; ++r) {
    std::vector<uint32_t> polygon;
    for (uint32_t k = 0; k < 6; ++k) polygon.push_back((r + k) % 6);
    expectCleanSplit(p, polygon, cross(u, v), 3.0f);
  }
}

TEST(PlyTriangulation, DegenerateAndOversizedPolygonsStillGiveTriangles) {
  // No area: a fan, so that the count of triangles stays n - 2 and nothing is lost silently.
  const std::vector<Vec3f> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  std::vector<uint32_t> tri;
  triangulatePolygon(line, {0, 1, 2, 3}, tri);
  EXPECT_EQ(tri, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  tri.clear();
  triangulatePolygon(line, {0, 1}, tri);
  EXPECT_TRUE(tri.empty());
}

std::string plyWithFaces(const std::string& faces, int faceCount) {
  return "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
         "property float z\nelement face " +
         std::to_string(faceCount) +
         "\nproperty list uchar int vertex_indices\nend_header\n"
         "4 0 0\n1 1 0\n0 4 0\n0 0 0\n" +
         faces;
}

TEST(PlyReader, ConcaveQuadRowKeepsItsArea) {
  const PlyMesh mesh = parsePly(plyWithFaces("4 0 1 2 3\n", 1));
  ASSERT_EQ(mesh.indices.size(), 6u);
  float area = 0;
  for (size_t t = 0; t < 2; ++t) {
    const Vec3f a = doubleArea(mesh.positions, mesh.indices, t);
    EXPECT_GT(a.z, 0);
    area += 0.5f * length(a);
  }
  EXPECT_NEAR(area, 4.0f, 1e-5f);
}

TEST(PlyReader, MalformedFaceRowsAreRefusedNotFatal) {
  // A row naming a vertex the file does not have (assimp's validation or ours says so).
  try {
    parsePly(plyWithFaces("3 0 1 9\n", 1));
    ADD_FAILURE() << "an index past the vertices was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
  }
  // Points and lines only: nothing to render.
  EXPECT_THROW(parsePly(plyWithFaces("2 0 1\n", 1)), std::runtime_error);
  // An empty face row: assimp's own triangulation aborted the process on it (the fuzzer's
  // finding, fuzz/corpus/scene_loader/ply-fuzzer-empty-face-row). Left out like a point.
  EXPECT_THROW(parsePly(plyWithFaces("0\n", 1)), std::runtime_error);
  // Rows run on after "end_header" on its own line (the fuzzer's input that made assimp spin
  // for minutes): refused before assimp sees it.
  std::string runOn = plyWithFaces("3 0 1 2\n", 1);
  runOn.replace(runOn.find("end_header\n"), 11, "end_header");
  EXPECT_THROW(parsePly(runOn), std::runtime_error);
  // Mixed: the empty row is dropped, the triangle kept.
  EXPECT_EQ(parsePly(plyWithFaces("0\n3 0 1 2\n", 2)).indices.size(), 3u);
}

}  // namespace
}  // namespace farm
