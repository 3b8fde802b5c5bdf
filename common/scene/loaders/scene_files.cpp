#include "common/scene/loaders/scene_files.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "common/scene/loaders/image_reader.h"
#include "common/scene/mesh_cleanup.h"

namespace farm {

namespace fs = std::filesystem;

std::string formatLoadMessage(const std::string& file, int line, const std::string& problem) {
  if (line > 0) return file + ":" + std::to_string(line) + ": " + problem;
  return file + ": " + problem;
}

SceneLoadError::SceneLoadError(const std::string& file, int line, const std::string& problem)
    : std::runtime_error(formatLoadMessage(file, line, problem)),
      file_(file),
      line_(line),
      problem_(problem) {}

fs::path sceneFilePath(const fs::path& sceneDir, const std::string& filename,
                       const std::string& kind, const std::string& file, int line) {
  fs::path named(filename);
  std::error_code ec;
  const fs::path root = fs::absolute(sceneDir, ec).lexically_normal();
  const fs::path inside = (root / named).lexically_normal().lexically_relative(root);
  if (named.is_absolute() || inside.empty() || *inside.begin() == "..")
    throw SceneLoadError(file, line,
                         kind + " '" + filename + "' is outside the scene's folder: " + kind +
                             "s must be inside it (with a relative path), as a farm submission "
                             "uploads that folder only");
  // Named in messages as the scene names its folder, which the coordinator strips from them.
  const fs::path path = sceneDir / named;
  if (!fs::exists(path, ec))
    throw SceneLoadError(file, line,
                         kind + " '" + filename + "' not found (looked for " + path.string() + ")");
  if (!fs::is_regular_file(path, ec))
    throw SceneLoadError(file, line, kind + " '" + filename + "' is not a regular file");
  return path;
}

std::string readSceneText(const std::string& path) {
  std::error_code ec;
  fs::file_status st = fs::status(path, ec);
  if (st.type() == fs::file_type::not_found) throw SceneLoadError(path, 0, "scene file not found");
  if (ec) throw SceneLoadError(path, 0, "cannot access: " + ec.message());
  if (!fs::is_regular_file(st)) throw SceneLoadError(path, 0, "not a regular file");
  return readSceneFile(path, "the scene file", path, 0);
}

std::string readSceneFile(const fs::path& path, const std::string& what, const std::string& file,
                          int line) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneLoadError(file, line, "cannot open " + what + ": " + std::strerror(errno));
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad()) throw SceneLoadError(file, line, "cannot read " + what);
  return bytes.str();
}

void finishMesh(const std::string& file, int line, const std::string& what, const Matrix4& toWorld,
                bool faceNormals, bool flip, std::vector<Vec3f> positions,
                std::vector<Vec3f> normals, std::vector<Vec2f> uvs, ShapeDescription* shape,
                std::vector<std::string>* warnings) {
  Matrix4 normalMatrix = toWorld.inverse().transpose();
  shape->positions.resize(positions.size());
  for (size_t i = 0; i < positions.size(); ++i) {
    shape->positions[i] = toWorld.applyPoint(positions[i]);
    if (!isFinite(shape->positions[i]))
      throw SceneLoadError(file, line, what + " has a non-finite vertex position");
  }
  // Before the normals: a needle's normal is noise and would spoil its vertices' averages.
  DegenerateTriangles degenerate = removeDegenerateTriangles(shape);
  if (degenerate.total() > 0 && warnings)
    warnings->push_back(formatLoadMessage(file, line, what + ": " + describe(degenerate)));
  if (shape->indices.empty())
    throw SceneLoadError(file, line, what + " contains only degenerate triangles");
  bool normalsOk = !faceNormals && normals.size() == positions.size();
  if (normalsOk) {
    shape->normals.resize(normals.size());
    for (size_t i = 0; i < normals.size() && normalsOk; ++i) {
      Vec3f w = normalMatrix.applyVector(normals[i]);
      float len = length(w);
      if (!(len > 0) || !std::isfinite(len)) normalsOk = false;  // fall back to computed ones
      shape->normals[i] = w / len;
    }
  }
  if (!normalsOk) shape->normals.clear();
  if (!faceNormals && !normalsOk) computeSmoothNormals(shape);
  shape->faceNormals = faceNormals;
  shape->uvs.clear();
  if (uvs.size() == positions.size()) {
    bool finite = std::all_of(uvs.begin(), uvs.end(), [](const Vec2f& t) {
      return std::isfinite(t.x) && std::isfinite(t.y);
    });
    if (!finite) throw SceneLoadError(file, line, what + " has a non-finite texture coordinate");
    shape->uvs = std::move(uvs);
  }
  if (flip) {
    for (size_t t = 0; t < shape->indices.size(); t += 3)
      std::swap(shape->indices[t + 1], shape->indices[t + 2]);
    for (Vec3f& n : shape->normals) n = -n;
  }
}

void computeSmoothNormals(ShapeDescription* shape) {
  std::vector<Vec3f> acc(shape->positions.size(), Vec3f(0.0f));
  std::vector<char> referenced(shape->positions.size(), 0);
  const auto& P = shape->positions;
  for (size_t t = 0; t < shape->indices.size(); t += 3) {
    uint32_t idx[3] = {shape->indices[t], shape->indices[t + 1], shape->indices[t + 2]};
    for (uint32_t i : idx) referenced[i] = 1;
    Vec3f n = cross(P[idx[1]] - P[idx[0]], P[idx[2]] - P[idx[0]]);
    float len = length(n);
    if (!(len > 0)) continue;  // degenerate: no direction to contribute
    n /= len;
    for (int k = 0; k < 3; ++k) {
      Vec3f e1 = P[idx[(k + 1) % 3]] - P[idx[k]], e2 = P[idx[(k + 2) % 3]] - P[idx[k]];
      float l1 = length(e1), l2 = length(e2);
      if (!(l1 > 0) || !(l2 > 0)) continue;
      float c = std::clamp(dot(e1, e2) / (l1 * l2), -1.0f, 1.0f);
      acc[idx[k]] += n * std::acos(c);
    }
  }
  for (size_t i = 0; i < acc.size(); ++i) {
    Vec3f& n = acc[i];
    float len = length(n);
    if (!(len > 0) || !std::isfinite(len)) {
      if (!referenced[i]) continue;  // no triangle uses it: its normal is never read
      // A vertex only on degenerate faces: without a direction for it, use geometric normals.
      shape->normals.clear();
      return;
    }
    n /= len;
  }
  shape->normals = std::move(acc);
}

Similarity similarityOf(const Matrix4& t, double* scale) {
  double col[3][3], len[3];
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) col[j][i] = t.m[i][j];
    len[j] = std::sqrt(col[j][0] * col[j][0] + col[j][1] * col[j][1] + col[j][2] * col[j][2]);
  }
  const double s = (len[0] + len[1] + len[2]) / 3.0;
  *scale = s;
  for (int j = 0; j < 3; ++j) {
    if (std::fabs(len[j] - s) > 1e-4 * s) return Similarity::NonUniformScale;
    for (int k = j + 1; k < 3; ++k) {
      const double d = col[j][0] * col[k][0] + col[j][1] * col[k][1] + col[j][2] * col[k][2];
      if (std::fabs(d) > 1e-4 * s * s) return Similarity::Shear;
    }
  }
  return Similarity::Uniform;
}

double determinant3(const Matrix4& t) {
  const auto& m = t.m;
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

}  // namespace farm

namespace farm {

std::shared_ptr<const TextureImage> TextureImageCache::load(const fs::path& sceneDir,
                                                            const std::string& filename,
                                                            TextureEncoding encoding,
                                                            const std::string& file, int line) {
  const fs::path path = sceneFilePath(sceneDir, filename, "texture", file, line);
  const std::string key = path.lexically_normal().string() + "|" + std::to_string(int(encoding));
  auto cached = images_.find(key);
  if (cached != images_.end()) return cached->second;
  const std::string bytes = readSceneFile(path, "texture '" + filename + "'", file, line);
  std::shared_ptr<TextureImage> image;
  try {
    image = readTextureImage(bytes, filename, encoding);
  } catch (const std::exception& e) {
    throw SceneLoadError(file, line, "cannot read texture '" + filename + "': " + e.what());
  }
  texelBytes_ += (long long)(image->bytes.size() + image->floats.size() * sizeof(float));
  if (texelBytes_ > kMaxTexelBytes)
    throw SceneLoadError(file, line,
                         "the scene's textures take more than " +
                             std::to_string(kMaxTexelBytes >> 30) + " GiB decoded");
  return images_.emplace(key, std::move(image)).first->second;
}

}  // namespace farm
