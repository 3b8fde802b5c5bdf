#pragma once
// Mitsuba 0.5/0.6's serialized meshes (".serialized"): little-endian, each mesh a four-byte
// header (0x041C, version 3 or 4) and a zlib stream (flags, a name in version 4, the vertex
// and triangle counts, positions, optional normals, texture coordinates and colours in single or
// double precision, uint32 triangle indices); the file ends with each mesh's byte offset and
// their count. Format as Mitsuba's documentation of its serialized plugin describes it; the
// reading is ours, bounded by the file's bytes and a budget, for files anyone may upload.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/math/vec.h"

namespace farm {

struct SerializedMesh {
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;     // one per position, or empty when the file has none
  std::vector<Vec2f> uvs;         // (u, v) as the file has them, or empty
  std::vector<uint32_t> indices;  // three per triangle, each below positions.size()
  bool faceNormals = false;       // the file asks for flat shading (flag 0x0010)
};

// Mesh `shapeIndex` of a serialized file's bytes. Throws std::runtime_error saying what is wrong
// (not a serialized file, an unknown version, an index beyond the file's meshes, a truncated or
// corrupt stream, an index out of range, more than maxElements vertices plus triangle corners).
SerializedMesh parseSerialized(const std::string& bytes, int shapeIndex, size_t maxElements);

}  // namespace farm
