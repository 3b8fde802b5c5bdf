#pragma once
// A Mitsuba 0.x scene file as XML, apart from what a scene means (mitsuba_loader.cpp builds the
// scene from it): the text kept so that every element's line is known, the errors that name it,
// the ids objects declare and the <ref>s that use them, and the readers of one element's values
// (numbers, colors, points, transforms) with the checks every value gets. The named parameters
// of an object are MitsubaProperties (mitsuba_properties.h). After pbrt-v4's split of the
// grammar from what it means (pbrt_parser.h is ours for pbrt), for Mitsuba's XML.
//
// Every error throws SceneLoadError (scene_files.h) naming the file and the line.
#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <map>
#include <pugixml.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "common/math/transform.h"
#include "common/math/vec.h"

namespace farm {

// Text helpers of Mitsuba's value syntax.
std::string toLower(std::string s);
std::string_view trim(std::string_view s);
// The whole token a finite number (strtod would take "1.5abc" as 1.5 and "nan" as NaN, which
// then poisons a render hours later).
bool parseFiniteDouble(std::string_view s, double* out);
bool parseInt(std::string_view s, long long* out);
// Mitsuba separates list entries by commas, blanks or both ("0.5, 0.5, 0.5", "1 0 0 0 ...").
std::vector<std::string> splitList(std::string_view s);

class MitsubaDocument {
 public:
  // Reads and parses the file; checks that the root is a <scene> of a Mitsuba 0.x version, and
  // that no element nests deeper than the loader may recurse.
  explicit MitsubaDocument(const std::string& path);
  MitsubaDocument(const MitsubaDocument&) = delete;
  MitsubaDocument& operator=(const MitsubaDocument&) = delete;

  const std::string& path() const { return path_; }
  const std::filesystem::path& dir() const { return dir_; }
  // "scene.xml:12": where an object came from, for messages about it after loading.
  std::string origin(const pugi::xml_node& node) const;
  pugi::xml_node root() const { return doc_.document_element(); }

  int lineOf(const pugi::xml_node& node) const { return lineOfOffset(node.offset_debug()); }
  [[noreturn]] void fail(const pugi::xml_node& node, const std::string& problem) const;
  // An element the loader does not read where it stands: known to Mitsuba but unsupported here,
  // or unknown.
  [[noreturn]] void failUnknownElement(const pugi::xml_node& node) const;

  // Ids: an object's id (if it has one) registered as a `kind` ("bsdf", "texture", ...) at
  // `index`; a <ref>'s object, which must be of `kind` and declared before it (the messages tell
  // a forward reference, an unknown id, a nested object and a wrong kind apart).
  void registerId(const pugi::xml_node& node, const std::string& kind, int index);
  int resolveRef(const pugi::xml_node& ref, const std::string& kind) const;

  // One element's values.
  const char* requireValue(const pugi::xml_node& n) const;
  void requireTag(const pugi::xml_node& n, std::initializer_list<const char*> tags) const;
  // A finite number that stays finite in float; `what` names it in the message.
  double number(const pugi::xml_node& n, std::string_view text, const std::string& what) const;
  long long integer(const pugi::xml_node& n, const char* name) const;  // an <integer>
  // <rgb>, <srgb> (also #rrggbb), <spectrum> (one value) or <float>/<integer> as a grey.
  Spectrum spectrumOf(const pugi::xml_node& n) const;
  // "x, y, z" in attribute `attr`, as Mitsuba's lookat writes vectors.
  Vec3f vectorFromList(const pugi::xml_node& n, const char* attr) const;
  // x/y/z attributes (each defaulting to `def`), or value="x y z".
  Vec3f xyzOf(const pugi::xml_node& n, float def) const;
  void checkAttributes(const pugi::xml_node& n, std::initializer_list<const char*> allowed) const;
  // A <transform> of matrix, translate, scale, rotate and lookat, each applied after the ones
  // before it; finite and invertible.
  Matrix4 transformOf(const pugi::xml_node& node) const;

 private:
  int lineOfOffset(ptrdiff_t offset) const;
  void checkVersion(const pugi::xml_node& root) const;
  void collectDeclaredIds(const pugi::xml_node& root);

  struct IdEntry {
    std::string kind;
    int index;
    int line;
  };

  std::string path_;
  std::filesystem::path dir_;
  std::string baseName_;
  std::string text_;
  std::vector<size_t> newlines_;
  pugi::xml_document doc_;
  std::map<std::string, IdEntry> ids_;
  std::map<std::string, int> declaredIds_;  // id -> line, over the whole document
};

}  // namespace farm
