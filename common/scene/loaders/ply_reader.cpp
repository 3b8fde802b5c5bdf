#include "common/scene/loaders/ply_reader.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <utility>
#include <vector>

namespace farm {
namespace {

// A strict reading of the header before assimp sees the file. assimp's PLY importer trusts
// what it is told: "element vertex 4000000000" in a 100-byte file makes it ask for 48 GB, and
// a malformed format or element line made it read past its buffer (both found by
// fuzz/fuzz_scene_loader; the inputs are in fuzz/corpus/scene_loader). So only headers made of
// PLY's own lines, each well-formed, with known types, reach it, and their counts must fit
// the bytes that follow: every element takes at least one byte (a binary property is one byte
// or more, an ASCII row ends with a newline), a binary element without lists exactly the sum
// of its properties' sizes.
int plyTypeSize(const std::string& type) {
  static const std::pair<const char*, int> kTypes[] = {
      {"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},  {"short", 2}, {"ushort", 2},
      {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},   {"int32", 4}, {"uint32", 4},
      {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  for (const auto& [name, size] : kTypes) {
    if (type == name) return size;
  }
  return 0;
}

void checkHeader(const std::string& bytes) {
  const size_t end = bytes.find("\nend_header");
  if (end == std::string::npos || end > (1 << 20)) {
    throw std::runtime_error("the header has no 'end_header' line");
  }
  const size_t bodyStart = bytes.find('\n', end + 1);
  // "end_header" alone on its line: assimp reads "end_header1 0 0" as no end of the header and
  // spun for minutes in its allocator on such a file
  // (fuzz/corpus/scene_loader/ply-end-header-run-on).
  const size_t lineEnd = bodyStart == std::string::npos ? bytes.size() : bodyStart;
  if (bytes.find_first_not_of(" \t\r", end + 11) < lineEnd) {
    throw std::runtime_error("the 'end_header' line has more on it than 'end_header'");
  }
  const uint64_t body = bodyStart == std::string::npos ? 0 : bytes.size() - bodyStart - 1;
  std::istringstream header(bytes.substr(0, end));
  std::string line;
  bool binary = false, sawFormat = false;
  struct Element {
    std::string name;
    uint64_t count = 0;
    uint64_t rowBytes = 0;  // binary: fixed bytes a row; lists add at least their count's size
    bool hasList = false, hasProperty = false;
  };
  std::vector<Element> elements;
  auto bad = [&](const std::string& why) {
    throw std::runtime_error("the header line '" + line.substr(0, 80) + "' " + why);
  };
  while (std::getline(header, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    for (char c : line) {
      if (static_cast<unsigned char>(c) < 0x20 && c != '\t') bad("holds a control character");
    }
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string word; words >> word;) w.push_back(word);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "ply") {
      if (w.size() != 1) bad("is not 'ply'");
    } else if (w[0] == "format") {
      if (w.size() != 3 || w[2] != "1.0" ||
          (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian")) {
        bad("is not 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      }
      binary = w[1] != "ascii";
      sawFormat = true;
    } else if (w[0] == "element") {
      if (w.size() != 3 || w[2].find_first_not_of("0123456789") != std::string::npos ||
          w[2].size() > 18) {
        bad("is not 'element NAME COUNT'");
      }
      elements.push_back({w[1], std::stoull(w[2])});
    } else if (w[0] == "property") {
      if (elements.empty()) bad("comes before any element");
      Element& e = elements.back();
      if (w.size() == 5 && w[1] == "list") {
        if (!plyTypeSize(w[2]) || !plyTypeSize(w[3])) bad("names an unknown type");
        e.rowBytes += uint64_t(plyTypeSize(w[2]));
        e.hasList = true;
      } else if (w.size() == 3 && plyTypeSize(w[1])) {
        e.rowBytes += uint64_t(plyTypeSize(w[1]));
      } else {
        bad("is not 'property TYPE NAME' or 'property list TYPE TYPE NAME'");
      }
      e.hasProperty = true;
    } else {
      bad("is not PLY's (ply, format, comment, obj_info, element, property, end_header)");
    }
  }
  if (!sawFormat) throw std::runtime_error("the header has no 'format' line");
  uint64_t least = 0;
  for (const Element& e : elements) {
    if (e.count > 0 && !e.hasProperty) {
      throw std::runtime_error("element '" + e.name + "' has no properties");
    }
    // At most 2^40 either way: the product below cannot overflow.
    if (e.count > (uint64_t(1) << 40)) {
      throw std::runtime_error("element '" + e.name + "' declares " + std::to_string(e.count) +
                               " rows");
    }
    least += e.count * (binary ? e.rowBytes : 1);
  }
  if (least > body) {
    throw std::runtime_error("the header declares elements that need at least " +
                             std::to_string(least) + " bytes but only " + std::to_string(body) +
                             " follow it (truncated, or a hostile count)");
  }
}

}  // namespace

void triangulatePolygon(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& polygon,
                        std::vector<uint32_t>& triangles) {
  const size_t n = polygon.size();
  auto fan = [&] {
    for (size_t k = 1; k + 1 < n; ++k)
      triangles.insert(triangles.end(), {polygon[0], polygon[k], polygon[k + 1]});
  };
  if (n < 3) return;
  if (n == 3 || n > kMaxEarClippedCorners) return fan();
  // Newell's normal: the polygon's vector area (twice it), exact for planar polygons and a
  // stable average for slightly warped ones.
  Vec3f normal(0.0f);
  for (size_t k = 0; k < n; ++k)
    normal += cross(positions[polygon[k]], positions[polygon[(k + 1) % n]]);
  const float ax = std::fabs(normal.x), ay = std::fabs(normal.y), az = std::fabs(normal.z);
  if (!(ax + ay + az > 0)) return fan();
  // Project onto the coordinate plane the normal is most along, flipped so that the polygon
  // winds counter-clockwise there.
  const int drop = ax >= ay && ax >= az ? 0 : (ay >= az ? 1 : 2);
  const float sign = (drop == 0 ? normal.x : drop == 1 ? normal.y : normal.z) > 0 ? 1.0f : -1.0f;
  std::vector<Vec2f> p(n);
  for (size_t k = 0; k < n; ++k) {
    const Vec3f& q = positions[polygon[k]];
    p[k] = drop == 0 ? Vec2f(q.y, q.z) : drop == 1 ? Vec2f(q.z, q.x) : Vec2f(q.x, q.y);
    p[k].y *= sign;
  }
  auto turn = [&](size_t a, size_t b, size_t c) {  // > 0: a, b, c turn left (counter-clockwise)
    return (p[b].x - p[a].x) * (p[c].y - p[a].y) - (p[b].y - p[a].y) * (p[c].x - p[a].x);
  };
  std::vector<size_t> left(n);
  for (size_t k = 0; k < n; ++k) left[k] = k;
  std::vector<uint32_t> clipped;
  while (left.size() > 3) {
    const size_t m = left.size();
    bool found = false;
    for (size_t k = 0; k < m && !found; ++k) {
      const size_t a = left[(k + m - 1) % m], b = left[k], c = left[(k + 1) % m];
      if (!(turn(a, b, c) > 0)) continue;  // a reflex (or straight) corner is no ear
      bool empty = true;
      for (size_t j : left) {
        if (j == a || j == b || j == c) continue;
        if (turn(a, b, j) >= 0 && turn(b, c, j) >= 0 && turn(c, a, j) >= 0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      clipped.insert(clipped.end(), {polygon[a], polygon[b], polygon[c]});
      left.erase(left.begin() + std::ptrdiff_t(k));
      found = true;
    }
    if (!found) return fan();  // not simple: no ear left, so no clean split exists
  }
  clipped.insert(clipped.end(), {polygon[left[0]], polygon[left[1]], polygon[left[2]]});
  triangles.insert(triangles.end(), clipped.begin(), clipped.end());
}

PlyMesh parsePly(const std::string& bytes) {
  if (bytes.compare(0, 4, "ply\n") != 0 && bytes.compare(0, 5, "ply\r\n") != 0)
    throw std::runtime_error("not a PLY file (it does not start with the line 'ply')");
  checkHeader(bytes);
  Assimp::Importer importer;
  // No post-processing: assimp reads the rows, we check and triangulate them. Its Triangulate
  // step aborts the process (an ai_assert compiled into Debian's build) on a face row with no
  // indices, which its ValidateDataStructure step lets through (fuzz/corpus/scene_loader has the
  // input), and a scene loader must not end the coordinator that reads it. The PLY importer
  // keeps the file's shared vertices, so nothing needs joining either.
  const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(),
                                                     aiProcess_ValidateDataStructure, "ply");
  if (!scene) {
    std::string reason = importer.GetErrorString();
    if (reason.empty()) reason = "unknown error";
    throw std::runtime_error(reason);
  }
  PlyMesh out;
  bool allNormals = true, allUvs = true;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    allNormals = allNormals && scene->mMeshes[m]->HasNormals();
    allUvs = allUvs && scene->mMeshes[m]->HasTextureCoords(0);
  }
  std::vector<uint32_t> polygon;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    const uint32_t base = uint32_t(out.positions.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      out.positions.emplace_back(p.x, p.y, p.z);
      if (allNormals) {
        const aiVector3D& n = mesh->mNormals[v];
        out.normals.emplace_back(n.x, n.y, n.z);
      }
      if (allUvs) {
        const aiVector3D& t = mesh->mTextureCoords[0][v];
        out.uvs.emplace_back(t.x, t.y);
      }
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      // Points and lines (and empty rows) have no surface to render: left out, as before.
      if (face.mNumIndices < 3) continue;
      polygon.clear();
      for (unsigned k = 0; k < face.mNumIndices; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices)
          throw std::runtime_error("face " + std::to_string(f) + " refers to vertex " +
                                   std::to_string(face.mIndices[k]) + ", out of range of " +
                                   std::to_string(mesh->mNumVertices) + " vertices");
        polygon.push_back(base + face.mIndices[k]);
      }
      triangulatePolygon(out.positions, polygon, out.indices);
    }
  }
  if (out.indices.empty()) throw std::runtime_error("no triangles (only points or lines)");
  return out;
}

}  // namespace farm
