#pragma once
// What the scene loaders (Mitsuba XML, pbrt) share: their error, the rule for files a scene
// names (meshes, textures), and the one path every mesh file's triangles take to world space.
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/math/transform.h"
#include "common/scene/loaders/image_reader.h"
#include "common/scene/scene_description.h"

namespace farm {

// what() is "FILE:LINE: problem", or "FILE: problem" when no line applies (unreadable file).
class SceneLoadError : public std::runtime_error {
 public:
  SceneLoadError(const std::string& file, int line, const std::string& problem);
  const std::string& file() const { return file_; }
  int line() const { return line_; }  // 1-based line; 0 when the problem has none
  const std::string& problem() const { return problem_; }

 private:
  std::string file_;
  int line_;
  std::string problem_;
};

std::string formatLoadMessage(const std::string& file, int line, const std::string& problem);

// Where a file named in a scene (`kind`: "mesh file", "texture") is: relative to the scene's
// folder and inside it, else a SceneLoadError at file:line. Inside, because the folder is what a
// farm submission uploads, and because a coordinator must not read its own files (an absolute
// path, or one climbing out with "..") for whoever submits a scene. Checked lexically, so a
// folder may hold symbolic links to its files. Missing and non-regular files are errors too.
std::filesystem::path sceneFilePath(const std::filesystem::path& sceneDir,
                                    const std::string& filename, const std::string& kind,
                                    const std::string& file, int line);

// The bytes of the scene file itself; SceneLoadErrors (without a line) when it is missing, not
// a regular file or unreadable.
std::string readSceneText(const std::string& path);

// The bytes of a file that sceneFilePath found: the only place the loaders open the files a
// scene names, so no reader ever opens one the scene's folder does not hold.
std::string readSceneFile(const std::filesystem::path& path, const std::string& what,
                          const std::string& file, int line);

// The texture images of one scene, read once however many textures name them (with the same
// encoding), and within a budget of decoded bytes: a small scene file may name a large image
// many times, or many large images.
class TextureImageCache {
 public:
  static constexpr long long kMaxTexelBytes = 4ll << 30;
  // The image `filename` names (through sceneFilePath, as a "texture"); SceneLoadErrors at
  // file:line when it is missing, unreadable, or over the budget.
  std::shared_ptr<const TextureImage> load(const std::filesystem::path& sceneDir,
                                           const std::string& filename, TextureEncoding encoding,
                                           const std::string& file, int line);

 private:
  std::map<std::string, std::shared_ptr<const TextureImage>> images_;
  long long texelBytes_ = 0;
};

// What every mesh read from a file goes through (`shape->indices` set; positions, normals and
// texture coordinates in the file's order, normals and uvs empty when the file has none): to
// world space, degenerate triangles out with a warning, the file's normals or smooth ones
// (unless faceNormals), texture coordinates kept when there is one per vertex, and flip
// (reverses the winding and the normals). Errors (non-finite positions, nothing left) are
// SceneLoadErrors at file:line naming `what`.
void finishMesh(const std::string& file, int line, const std::string& what, const Matrix4& toWorld,
                bool faceNormals, bool flip, std::vector<Vec3f> positions,
                std::vector<Vec3f> normals, std::vector<Vec2f> uvs, ShapeDescription* shape,
                std::vector<std::string>* warnings);

// Mitsuba's and pbrt's smooth vertex normals for meshes without them: the angle-weighted
// average of the adjacent faces' normals. Leaves normals empty when a vertex has none.
void computeSmoothNormals(ShapeDescription* shape);

// The determinant of the upper 3x3 block: negative for a mirroring transform.
double determinant3(const Matrix4& t);

// Whether the upper 3x3 block is a rotation (or reflection) times a uniform scale, to a relative
// 1e-4; *scale receives the (mean) scale. Spheres and cameras take only such transformations.
enum class Similarity { Uniform, NonUniformScale, Shear };
Similarity similarityOf(const Matrix4& t, double* scale);

}  // namespace farm
