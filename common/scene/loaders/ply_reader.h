#pragma once
// PLY meshes (ASCII and binary, Stanford's format) through Open Asset Import Library: the
// triangles of every mesh in the file, in the file's own coordinates, with per-vertex normals
// and texture coordinates where the file has them. Polygons are triangulated here (not by assimp,
// whose step aborts on some malformed rows); points and lines are left out, and a mesh made only
// of them is refused, as it has no surface to render. Only PLY: the file must start as
// one, and assimp reads it from memory with its PLY importer alone, so no other format's importer
// (some of which open further files the first one names) ever sees it.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/math/vec.h"

namespace farm {

struct PlyMesh {
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;     // one per position, or empty when the file has none
  std::vector<Vec2f> uvs;         // texture coordinates (u, v) as the file has them, or empty
  std::vector<uint32_t> indices;  // three per triangle
};

// The mesh in a PLY file's bytes. Throws std::runtime_error with assimp's reason (or ours) when
// they are not a readable PLY.
PlyMesh parsePly(const std::string& bytes);

// Appends the triangles of one planar (or nearly planar) polygon, given as indices into
// positions in its winding order, to triangles, keeping that winding. Ear clipping in the plane
// of the polygon's Newell normal, so concave polygons come out without overlapping triangles;
// a degenerate polygon (no area), one that is not simple, or one of more than
// kMaxEarClippedCorners corners is split as a fan from its first corner instead.
inline constexpr size_t kMaxEarClippedCorners = 256;
void triangulatePolygon(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& polygon,
                        std::vector<uint32_t>& triangles);

}  // namespace farm
