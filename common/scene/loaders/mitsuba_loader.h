#pragma once
// Mitsuba 0.6 XML scenes (the subset the farm renders) to a SceneDescription in world space.
//
// Supported: <integrator> (maxDepth only), one perspective <sensor> with <film> and <rfilter>
// (tent, box), <bsdf> diffuse / twosided / dielectric / roughconductor (declared at top level with
// an id and used through <ref>, or inline in a shape), <shape> rectangle / cube / sphere / obj with
// an optional area <emitter>, and <transform> built from matrix, translate, scale, rotate, lookat.
// Anything else that would change the picture is an error rather than silently ignored: a render
// that quietly differs from the scene is worse than one that refuses to start.
#include <stdexcept>
#include <string>

#include "common/scene/scene_description.h"

namespace farm {

// what() is "FILE:LINE: problem", or "FILE: problem" when no line applies (unreadable file).
class SceneLoadError : public std::runtime_error {
 public:
  SceneLoadError(const std::string& file, int line, const std::string& problem);
  const std::string& file() const { return file_; }
  int line() const { return line_; }  // 1-based XML line; 0 when the problem has none
  const std::string& problem() const { return problem_; }

 private:
  std::string file_;
  int line_;
  std::string problem_;
};

// Throws SceneLoadError for anything it cannot load faithfully. Mesh paths are relative to the
// directory of the XML file.
SceneDescription loadMitsubaScene(const std::string& path);

}  // namespace farm
