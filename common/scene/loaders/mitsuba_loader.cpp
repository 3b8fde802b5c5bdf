#include "common/scene/loaders/mitsuba_loader.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <pugixml.hpp>
#include <sstream>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "common/scene/loaders/grid_volume_reader.h"
#include "common/scene/loaders/ply_reader.h"
#include "common/scene/loaders/scene_files.h"
#include "common/scene/loaders/serialized_reader.h"
#include "common/scene/loaders/vdb_reader.h"
#include "common/scene/medium.h"
#include "common/scene/mesh_cleanup.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

std::string toLower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

// Strict number parsing: the whole token must be a number, and a finite one. (strtod would take
// "1.5abc" as 1.5 and "nan" as NaN, which then poisons a render hours later.)
bool parseFiniteDouble(std::string_view s, double* out) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  double v = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

bool parseInt(std::string_view s, long long* out) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), *out);
  return ec == std::errc() && end == s.data() + s.size();
}

// Mitsuba separates list entries by commas, blanks or both ("0.5, 0.5, 0.5", "1 0 0 0 ...").
std::vector<std::string> splitList(std::string_view s) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == ',' || std::isspace(static_cast<unsigned char>(c))) {
      if (!cur.empty()) out.push_back(std::move(cur));
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  if (!cur.empty()) out.push_back(std::move(cur));
  return out;
}

float srgbToLinear(double v) {
  return float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
}

// Named indices of refraction of Mitsuba's dielectric plugins (its documentation's table).
const std::map<std::string, double>& namedIors() {
  static const std::map<std::string, double> table = {
      {"vacuum", 1.0},      {"helium", 1.000036},        {"hydrogen", 1.000132},
      {"air", 1.000277},    {"carbon dioxide", 1.00045}, {"water", 1.3330},
      {"acetone", 1.36},    {"ethanol", 1.361},          {"carbon tetrachloride", 1.461},
      {"glycerol", 1.4729}, {"benzene", 1.501},          {"silicone oil", 1.52045},
      {"bromine", 1.661},   {"water ice", 1.31},         {"fused quartz", 1.458},
      {"pyrex", 1.470},     {"acrylic glass", 1.49},     {"polypropylene", 1.49},
      {"bk7", 1.5046},      {"sodium chloride", 1.544},  {"amber", 1.55},
      {"pet", 1.5750},      {"diamond", 2.419},
  };
  return table;
}

// Copper, Mitsuba's default conductor, as RGB (the values its exporter writes for "Cu").
constexpr double kPiDouble = 3.14159265358979323846;

const Spectrum kCopperEta{0.200438f, 0.924033f, 1.10221f};
const Spectrum kCopperK{3.91295f, 2.45285f, 2.14219f};

bool isPropertyTag(std::string_view tag) {
  static const char* const kTags[] = {"float",    "integer",   "boolean",  "string",
                                      "point",    "vector",    "rgb",      "srgb",
                                      "spectrum", "blackbody", "transform"};
  for (const char* t : kTags)
    if (tag == t) return true;
  return false;
}

// The named parameters of one object element (<float name=...> and friends), with a record of
// which ones were read so that the rest can be reported.
struct PropertySet {
  std::vector<std::pair<std::string, pugi::xml_node>> entries;
  std::vector<bool> used;

  pugi::xml_node take(const char* name) {
    for (size_t i = 0; i < entries.size(); ++i)
      if (entries[i].first == name) {
        used[i] = true;
        return entries[i].second;
      }
    return {};
  }
  bool has(const char* name) const {
    for (const auto& e : entries)
      if (e.first == name) return true;
    return false;
  }
};

class MitsubaLoader {
 public:
  explicit MitsubaLoader(const std::string& path) : path_(path) {}

  SceneDescription load() {
    readFile();
    parseXml();
    scene_.sourcePath = path_;
    pugi::xml_node root = doc_.document_element();
    if (std::string_view(root.name()) != "scene")
      fail(root, "the root element must be <scene>, not <" + std::string(root.name()) + ">");
    checkVersion(root);
    collectDeclaredIds(root);
    scene_.strictNormals = false;  // Mitsuba's default, without an integrator that says otherwise
    bool sawSensor = false, sawIntegrator = false;
    for (pugi::xml_node child : root.children()) {
      if (child.type() != pugi::node_element) continue;
      std::string_view tag = child.name();
      if (tag == "integrator") {
        if (sawIntegrator) fail(child, "more than one <integrator>");
        sawIntegrator = true;
        parseIntegrator(child);
      } else if (tag == "sensor") {
        if (sawSensor) fail(child, "more than one <sensor>; the farm renders one camera");
        sawSensor = true;
        parseSensor(child);
      } else if (tag == "bsdf") {
        int index = addBsdf(parseBsdf(child));
        registerId(child, "bsdf", index);
      } else if (tag == "shape") {
        parseShape(child);
      } else if (tag == "emitter") {
        parseTopLevelEmitter(child);
      } else if (tag == "texture") {
        registerId(child, "texture", parseTexture(child));
      } else if (tag == "medium") {
        registerId(child, "medium", parseMedium(child));
      } else {
        failUnknownElement(child);
      }
    }
    return std::move(scene_);
  }

 private:
  // ---- Errors and line numbers ----

  int lineOfOffset(ptrdiff_t offset) const {
    if (offset < 0) return 0;
    auto it = std::upper_bound(newlines_.begin(), newlines_.end(), size_t(offset));
    return int(it - newlines_.begin()) + 1;
  }
  int lineOf(const pugi::xml_node& node) const { return lineOfOffset(node.offset_debug()); }

  [[noreturn]] void fail(const pugi::xml_node& node, const std::string& problem) const {
    throw SceneLoadError(path_, node ? lineOf(node) : 0, problem);
  }
  [[noreturn]] void failUnknownElement(const pugi::xml_node& node) const {
    static const char* const kKnownButUnsupported[] = {"medium", "phase",   "subsurface", "include",
                                                       "alias",  "default", "volume"};
    std::string tag = node.name();
    for (const char* t : kKnownButUnsupported)
      if (tag == t) fail(node, "<" + tag + "> is not supported here");
    fail(node, "unknown element <" + tag + ">");
  }

  // ---- File and XML ----

  void readFile() {
    text_ = readSceneText(path_);
    for (size_t i = 0; i < text_.size(); ++i)
      if (text_[i] == '\n') newlines_.push_back(i);
    dir_ = fs::path(path_).parent_path();
    baseName_ = fs::path(path_).filename().string();
  }

  void parseXml() {
    // From our own buffer so that offsets (and so line numbers) refer to the file's bytes.
    pugi::xml_parse_result r =
        doc_.load_buffer(text_.data(), text_.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!r)
      throw SceneLoadError(path_, lineOfOffset(r.offset),
                           std::string("malformed XML: ") + r.description());
  }

  void checkVersion(const pugi::xml_node& root) {
    pugi::xml_attribute v = root.attribute("version");
    if (!v) fail(root, "<scene> has no version attribute (expected a Mitsuba 0.x version)");
    std::vector<std::string> parts;
    std::string cur;
    for (char c : std::string(v.value())) {
      if (c == '.') {
        parts.push_back(cur);
        cur.clear();
      } else {
        cur.push_back(c);
      }
    }
    parts.push_back(cur);
    long long major = 0;
    for (const std::string& p : parts) {
      long long n;
      if (!parseInt(p, &n) || n < 0)
        fail(root, "invalid scene version '" + std::string(v.value()) + "'");
    }
    parseInt(parts[0], &major);
    // Mitsuba 2 and 3 renamed most parameters (to_world, ...): refuse rather than misread them.
    if (major != 0)
      fail(root, "scene version " + std::string(v.value()) +
                     " is not Mitsuba 0.x; only Mitsuba 0.5/0.6 scenes are supported");
  }

  // Every id in the document, so that a forward reference gets a precise message. The walk is
  // iterative and bounds the nesting depth: the parsing that follows recurses along nested
  // objects, and a scene uploaded by anyone must not be able to overflow the stack.
  void collectDeclaredIds(const pugi::xml_node& root) {
    struct Walker : pugi::xml_tree_walker {
      const MitsubaLoader* loader;
      std::map<std::string, int>* ids;
      pugi::xml_node tooDeep;
      bool for_each(pugi::xml_node& node) override {
        if (node.type() != pugi::node_element) return true;
        if (depth() > kMaxDepth) {
          tooDeep = node;
          return false;
        }
        pugi::xml_attribute id = node.attribute("id");
        if (id && std::string_view(node.name()) != "ref")
          ids->emplace(id.value(), loader->lineOf(node));
        return true;
      }
    } walker;
    walker.loader = this;
    walker.ids = &declaredIds_;
    pugi::xml_node start = root;
    start.traverse(walker);
    if (walker.tooDeep) fail(walker.tooDeep, "elements nested too deeply");
  }

  static constexpr int kMaxDepth = 64;

  struct IdEntry {
    std::string kind;
    int index;
    int line;
  };

  void registerId(const pugi::xml_node& node, const std::string& kind, int index) {
    pugi::xml_attribute id = node.attribute("id");
    if (!id) return;
    std::string key = id.value();
    if (key.empty()) fail(node, "empty id attribute");
    auto it = ids_.find(key);
    if (it != ids_.end())
      fail(node, "duplicate id '" + key + "' (first declared at line " +
                     std::to_string(it->second.line) + ")");
    ids_.emplace(key, IdEntry{kind, index, lineOf(node)});
  }

  // The object of `kind` ("bsdf", "texture") a <ref> names, checking that it is one.
  int resolveRef(const pugi::xml_node& ref, const std::string& kind) {
    pugi::xml_attribute id = ref.attribute("id");
    if (!id) fail(ref, "<ref> without an id attribute");
    std::string key = id.value();
    auto it = ids_.find(key);
    if (it == ids_.end()) {
      auto declared = declaredIds_.find(key);
      if (declared == declaredIds_.end()) fail(ref, "<ref> to unknown id '" + key + "'");
      if (declared->second >= lineOf(ref))
        fail(ref, "<ref id=\"" + key + "\"> comes before its declaration at line " +
                      std::to_string(declared->second) + " (declare objects before using them)");
      fail(ref, "<ref id=\"" + key + "\">: the object declared at line " +
                    std::to_string(declared->second) +
                    " cannot be referenced (only top-level and shape-level bsdfs and top-level "
                    "textures and media can)");
    }
    if (it->second.kind != kind)
      fail(ref, "<ref id=\"" + key + "\"> names a <" + it->second.kind + "> (line " +
                    std::to_string(it->second.line) + "), but a <" + kind + "> is needed here");
    return it->second.index;
  }
  int resolveBsdfRef(const pugi::xml_node& ref) { return resolveRef(ref, "bsdf"); }

  // ---- Properties ----

  // Splits an object's children into named properties and nested elements (objects, refs).
  PropertySet collectProperties(const pugi::xml_node& node,
                                std::vector<pugi::xml_node>* nested) const {
    PropertySet props;
    for (pugi::xml_node child : node.children()) {
      if (child.type() != pugi::node_element) continue;
      if (isPropertyTag(child.name())) {
        pugi::xml_attribute name = child.attribute("name");
        if (!name || !*name.value())
          fail(child, "<" + std::string(child.name()) + "> without a name attribute");
        if (props.has(name.value()))
          fail(child, "parameter '" + std::string(name.value()) + "' given twice");
        props.entries.emplace_back(name.value(), child);
        props.used.push_back(false);
      } else if (nested) {
        nested->push_back(child);
      } else {
        failUnknownElement(child);
      }
    }
    return props;
  }

  // Parameters nobody read would be silently ignored: refuse them where they matter.
  void rejectUnused(const PropertySet& props, const std::string& what) const {
    for (size_t i = 0; i < props.entries.size(); ++i)
      if (!props.used[i])
        fail(props.entries[i].second,
             "unsupported parameter '" + props.entries[i].first + "' for " + what);
  }

  std::string paramName(const pugi::xml_node& n) const { return n.attribute("name").value(); }

  const char* requireValue(const pugi::xml_node& n) const {
    pugi::xml_attribute v = n.attribute("value");
    if (!v)
      fail(n,
           "<" + std::string(n.name()) + " name=\"" + paramName(n) + "\"> has no value attribute");
    return v.value();
  }

  void requireTag(const pugi::xml_node& n, std::initializer_list<const char*> tags) const {
    std::string allowed;
    for (const char* t : tags) {
      if (std::string_view(n.name()) == t) return;
      if (!allowed.empty()) allowed += " or ";
      allowed += std::string("<") + t + ">";
    }
    fail(n, "parameter '" + paramName(n) + "' must be " + allowed + ", not <" + n.name() + ">");
  }

  double number(const pugi::xml_node& n, std::string_view text, const std::string& what) const {
    double v;
    if (!parseFiniteDouble(text, &v))
      fail(n, what + ": '" + std::string(text) + "' is not a finite number");
    // Everything ends up in float (positions, colors, angles): it must stay finite there too.
    if (std::fabs(v) > double(std::numeric_limits<float>::max()))
      fail(n, what + ": '" + std::string(text) + "' is out of range");
    return v;
  }

  bool getBoolean(PropertySet& props, const char* name, bool def) const {
    pugi::xml_node n = props.take(name);
    if (!n) return def;
    requireTag(n, {"boolean"});
    std::string v = toLower(std::string(trim(requireValue(n))));
    if (v == "true") return true;
    if (v == "false") return false;
    fail(n, std::string("parameter '") + name + "': '" + requireValue(n) +
                "' is not a boolean (true or false)");
  }

  std::string getString(PropertySet& props, const char* name, const std::string& def,
                        pugi::xml_node* where = nullptr) const {
    pugi::xml_node n = props.take(name);
    if (where) *where = n;
    if (!n) return def;
    requireTag(n, {"string"});
    return requireValue(n);
  }

  Spectrum spectrumOf(const pugi::xml_node& n) const {
    std::string what = "parameter '" + paramName(n) + "'";
    std::string_view tag = n.name();
    std::string value = requireValue(n);
    if (tag == "float" || tag == "integer") return Spectrum(float(number(n, value, what)));
    if (tag == "rgb" || tag == "srgb") {
      if (tag == "srgb" && !trim(value).empty() && trim(value).front() == '#') {
        std::string hex(trim(value).substr(1));
        if (hex.size() != 6 || hex.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos)
          fail(n, what + ": '" + value + "' is not an #rrggbb color");
        Spectrum s;
        for (int i = 0; i < 3; ++i)
          s[i] = srgbToLinear(std::stoi(hex.substr(2 * i, 2), nullptr, 16) / 255.0);
        return s;
      }
      std::vector<std::string> parts = splitList(value);
      if (parts.size() != 1 && parts.size() != 3)
        fail(n, what + ": '" + value + "' needs 3 numbers (r, g, b) or 1");
      Spectrum s;
      for (int i = 0; i < 3; ++i) {
        double v = number(n, parts[parts.size() == 1 ? 0 : i], what);
        s[i] = tag == "srgb" ? srgbToLinear(v) : float(v);
      }
      return s;
    }
    if (tag == "spectrum") {
      if (value.find(':') != std::string::npos)
        fail(n, what + ": sampled spectra (wavelength:value) are not supported; use <rgb>");
      std::vector<std::string> parts = splitList(value);
      if (parts.size() != 1)
        fail(n, what + ": <spectrum> takes a single value here; use <rgb> for colors");
      return Spectrum(float(number(n, parts[0], what)));
    }
    fail(n, what + " must be <rgb>, <srgb>, <spectrum> or <float>, not <" + std::string(tag) + ">");
  }

  // A color that must be finite and non-negative (reflectances, radiance, conductor indices).
  Spectrum getSpectrum(PropertySet& props, const char* name, const Spectrum& def) const {
    pugi::xml_node n = props.take(name);
    if (!n) return def;
    Spectrum s = spectrumOf(n);
    if (s.x < 0 || s.y < 0 || s.z < 0)
      fail(n, std::string("parameter '") + name + "' must not be negative");
    return s;
  }

  // "x, y, z" as Mitsuba's lookat writes vectors.
  Vec3f vectorFromList(const pugi::xml_node& n, const char* attr) const {
    pugi::xml_attribute a = n.attribute(attr);
    if (!a) fail(n, "<" + std::string(n.name()) + "> needs a '" + attr + "' attribute");
    std::vector<std::string> parts = splitList(a.value());
    if (parts.size() != 3) fail(n, std::string(attr) + ": '" + a.value() + "' needs 3 numbers");
    std::string what = std::string(n.name()) + " " + attr;
    return {float(number(n, parts[0], what)), float(number(n, parts[1], what)),
            float(number(n, parts[2], what))};
  }

  // x/y/z attributes (each defaulting to `def`), or value="x y z".
  Vec3f xyzOf(const pugi::xml_node& n, float def) const {
    if (n.attribute("value")) {
      if (n.attribute("x") || n.attribute("y") || n.attribute("z"))
        fail(n, "<" + std::string(n.name()) + "> has both value and x/y/z attributes");
      return vectorFromList(n, "value");
    }
    Vec3f v(def);
    const char* names[3] = {"x", "y", "z"};
    for (int i = 0; i < 3; ++i)
      if (pugi::xml_attribute a = n.attribute(names[i]))
        v[i] = float(number(n, a.value(), std::string(n.name()) + " " + names[i]));
    return v;
  }

  void checkAttributes(const pugi::xml_node& n, std::initializer_list<const char*> allowed) const {
    for (pugi::xml_attribute a : n.attributes()) {
      bool ok = false;
      for (const char* s : allowed) ok = ok || std::string_view(a.name()) == s;
      if (!ok)
        fail(n, "unexpected attribute '" + std::string(a.name()) + "' on <" + n.name() + ">");
    }
  }

  Vec3f getPoint(PropertySet& props, const char* name, const Vec3f& def) const {
    pugi::xml_node n = props.take(name);
    if (!n) return def;
    requireTag(n, {"point", "vector"});
    checkAttributes(n, {"name", "x", "y", "z", "value"});
    return xyzOf(n, 0.0f);
  }

  Matrix4 transformOf(const pugi::xml_node& node) const {
    requireTag(node, {"transform"});
    Matrix4 m = Matrix4::identity();
    for (pugi::xml_node op : node.children()) {
      if (op.type() != pugi::node_element) continue;
      std::string_view tag = op.name();
      Matrix4 t;
      if (tag == "matrix") {
        checkAttributes(op, {"value"});
        std::vector<std::string> parts = splitList(requireValue(op));
        if (parts.size() != 16)
          fail(op,
               "<matrix> needs 16 numbers (row-major 4x4), got " + std::to_string(parts.size()));
        for (int i = 0; i < 16; ++i) t.m[i / 4][i % 4] = number(op, parts[i], "matrix entry");
        const auto& last = t.m[3];
        if (last[0] != 0 || last[1] != 0 || last[2] != 0 || last[3] != 1)
          fail(op, "<matrix> is not affine: its last row must be 0 0 0 1");
      } else if (tag == "translate") {
        checkAttributes(op, {"x", "y", "z", "value"});
        t = Matrix4::translate(xyzOf(op, 0.0f));
      } else if (tag == "scale") {
        checkAttributes(op, {"x", "y", "z", "value"});
        pugi::xml_attribute v = op.attribute("value");
        if (v && splitList(v.value()).size() == 1 && !op.attribute("x") && !op.attribute("y") &&
            !op.attribute("z"))
          t = Matrix4::scale(Vec3f(float(number(op, v.value(), "scale value"))));
        else
          t = Matrix4::scale(xyzOf(op, 1.0f));
      } else if (tag == "rotate") {
        checkAttributes(op, {"x", "y", "z", "angle", "value"});
        Vec3f axis = xyzOf(op, 0.0f);
        if (axis.x == 0 && axis.y == 0 && axis.z == 0) fail(op, "<rotate> with a zero axis");
        pugi::xml_attribute angle = op.attribute("angle");
        if (!angle) fail(op, "<rotate> needs an angle attribute (degrees)");
        t = Matrix4::rotate(axis, number(op, angle.value(), "rotate angle"));
      } else if (tag == "lookat" || tag == "lookAt") {
        checkAttributes(op, {"origin", "target", "up"});
        Vec3f origin = vectorFromList(op, "origin"), target = vectorFromList(op, "target");
        Vec3f dir = target - origin;
        if (dir.x == 0 && dir.y == 0 && dir.z == 0) fail(op, "<lookat> origin equals target");
        Vec3f up;
        if (op.attribute("up")) {
          up = vectorFromList(op, "up");
        } else {
          // Mitsuba picks some up vector perpendicular to the view direction when none is given.
          Frame f(normalize(dir));
          up = f.s;
        }
        t = Matrix4::lookAt(origin, target, up);
        if (!t.isFinite()) fail(op, "<lookat> up vector is zero or parallel to the view direction");
      } else {
        fail(op, "unknown element <" + std::string(tag) + "> in <transform>");
      }
      m = t * m;  // each operation applies after the ones before it
    }
    if (!m.isFinite()) fail(node, "transform has non-finite entries");
    if (!m.inverse().isFinite()) fail(node, "transform is singular (not invertible)");
    return m;
  }

  // ---- Objects ----

  void parseIntegrator(const pugi::xml_node& node) {
    // Only the path length and the shading-normal convention matter to the farm: it picks its own
    // algorithms (see the render plan).
    std::vector<pugi::xml_node> nested;
    PropertySet props = collectProperties(node, &nested);
    // Mitsuba's Monte Carlo integrators default strictNormals to false (set before the scene is
    // read); the file's value holds, from whichever integrator, wrapping or wrapped, says it.
    scene_.strictNormals = getBoolean(props, "strictNormals", scene_.strictNormals);
    if (pugi::xml_node n = props.take("maxDepth")) {
      long long depth = getIntegerFrom(n, "maxDepth");
      if (depth < -1 || depth > 1000000) fail(n, "maxDepth must be -1 (unbounded) or >= 0");
      scene_.maxDepth = int(depth);
      return;
    }
    // Wrapping integrators (adaptive, irrcache, ...) hold the real one inside.
    for (const pugi::xml_node& child : nested)
      if (std::string_view(child.name()) == "integrator") parseIntegrator(child);
  }

  long long getIntegerFrom(const pugi::xml_node& n, const char* name) const {
    requireTag(n, {"integer"});
    long long v;
    if (!parseInt(requireValue(n), &v))
      fail(n, std::string("parameter '") + name + "': '" + requireValue(n) + "' is not an integer");
    return v;
  }

  void parseSensor(const pugi::xml_node& node) {
    std::string type = node.attribute("type").as_string();
    if (type != "perspective" && type != "thinlens")
      fail(node,
           "unknown or unsupported sensor type '" + type + "' (perspective and thinlens only)");
    registerId(node, "sensor", 0);
    std::vector<pugi::xml_node> nested;
    PropertySet props = collectProperties(node, &nested);
    CameraDescription& cam = scene_.camera;
    if (pugi::xml_node t = props.take("toWorld")) cam.toWorld = transformOf(t);

    // The film first: Mitsuba resolves "smaller"/"larger" against the film's aspect ratio.
    bool sawFilm = false, sawCameraMedium = false;
    for (const pugi::xml_node& child : nested) {
      std::string_view tag = child.name();
      if (tag == "film") {
        if (sawFilm) fail(child, "more than one <film>");
        sawFilm = true;
        parseFilm(child);
      } else if (tag == "sampler") {
        // The farm chooses its own sampling.
      } else if (tag == "medium" || tag == "ref") {
        // The medium the camera sits in (Mitsuba's sensor medium).
        if (sawCameraMedium) fail(child, "a sensor takes one medium");
        sawCameraMedium = true;
        cam.medium = tag == "ref" ? resolveRef(child, "medium") : parseMedium(child);
      } else {
        failUnknownElement(child);
      }
    }

    pugi::xml_node fovNode = props.take("fov");
    pugi::xml_node focalNode = props.take("focalLength");
    if (fovNode && focalNode) fail(focalNode, "give either fov or focalLength, not both");
    pugi::xml_node axisNode;
    std::string axis = toLower(getString(props, "fovAxis", "x", &axisNode));
    if (axis == "x") {
      cam.fovAxis = FovAxis::X;
    } else if (axis == "y") {
      cam.fovAxis = FovAxis::Y;
    } else if (axis == "smaller") {
      cam.fovAxis = FovAxis::Smaller;
    } else if (axis == "larger") {
      cam.fovAxis = FovAxis::Larger;
    } else if (axis == "diagonal") {
      cam.fovAxis = FovAxis::Diagonal;
    } else {
      fail(axisNode, "fovAxis '" + axis + "' is not one of x, y, smaller, larger, diagonal");
    }
    double fov;
    if (fovNode) {
      requireTag(fovNode, {"float", "integer"});
      fov = number(fovNode, requireValue(fovNode), "parameter 'fov'");
      if (!(fov > 0 && fov < 180)) fail(fovNode, "fov must be in (0, 180) degrees");
    } else {
      // Mitsuba: a 35 mm film equivalent focal length ("50mm" by default) sets the diagonal fov.
      double focal = 50;
      if (focalNode) {
        requireTag(focalNode, {"string", "float", "integer"});
        std::string f(trim(requireValue(focalNode)));
        if (f.size() > 2 && toLower(f.substr(f.size() - 2)) == "mm") f.resize(f.size() - 2);
        focal = number(focalNode, f, "parameter 'focalLength'");
        if (!(focal > 0)) fail(focalNode, "focalLength must be positive");
      }
      fov = 2.0 * std::atan(std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * focal)) *
            (180.0 / kPiDouble);
      cam.fovAxis = FovAxis::Diagonal;
    }
    cam.fovDegrees = float(fov);
    if (type == "thinlens") {
      // Mitsuba's thinlens: an aperture of this radius, focused at this world-space distance.
      for (const char* name : {"apertureRadius", "focusDistance"}) {
        pugi::xml_node n = props.take(name);
        if (!n) fail(node, std::string("a thinlens sensor needs <float name=\"") + name + "\">");
        requireTag(n, {"float", "integer"});
        double v = number(n, requireValue(n), std::string("parameter '") + name + "'");
        if (!(v > 0)) fail(n, std::string(name) + " must be > 0");
        (name[0] == 'a' ? cam.lensRadius : cam.focusDistance) = float(v);
      }
    }
    // Clip planes, shutter times and focus distance do not change a pinhole render.
  }

  void parseFilm(const pugi::xml_node& node) {
    std::vector<pugi::xml_node> nested;
    PropertySet props = collectProperties(node, &nested);
    CameraDescription& cam = scene_.camera;
    long long width = cam.width, height = cam.height;
    pugi::xml_node widthNode = props.take("width"), heightNode = props.take("height");
    if (widthNode) width = getIntegerFrom(widthNode, "width");
    if (heightNode) height = getIntegerFrom(heightNode, "height");
    constexpr long long kMaxSide = 65536, kMaxPixels = 1LL << 28;
    if (width < 1 || width > kMaxSide)
      fail(widthNode ? widthNode : node,
           "film width " + std::to_string(width) + " is not in [1, 65536]");
    if (height < 1 || height > kMaxSide)
      fail(heightNode ? heightNode : node,
           "film height " + std::to_string(height) + " is not in [1, 65536]");
    if (width * height > kMaxPixels)
      fail(node, "film of " + std::to_string(width) + "x" + std::to_string(height) +
                     " pixels exceeds 2^28 pixels");
    cam.width = int(width);
    cam.height = int(height);
    // Other film parameters (file format, gamma, banner, crop) are about Mitsuba's output.
    bool sawFilter = false;
    for (const pugi::xml_node& child : nested) {
      if (std::string_view(child.name()) != "rfilter") failUnknownElement(child);
      if (sawFilter) fail(child, "more than one <rfilter>");
      sawFilter = true;
      std::string type = child.attribute("type").as_string();
      if (type == "tent") {
        cam.filter = FilterType::Tent;
      } else if (type == "box") {
        cam.filter = FilterType::Box;
      } else if (type == "gaussian") {
        // Mitsuba's gaussian: exp(-x^2 / (2 stddev^2)), less its value at 4 standard deviations,
        // where it is cut off.
        std::vector<pugi::xml_node> filterNested;
        PropertySet filterProps = collectProperties(child, &filterNested);
        for (const pugi::xml_node& n : filterNested) failUnknownElement(n);
        double stddev = 0.5;
        if (pugi::xml_node n = filterProps.take("stddev")) {
          requireTag(n, {"float", "integer"});
          stddev = number(n, requireValue(n), "parameter 'stddev'");
          // Its radius 4 stddev must reach half a pixel, so that every film point reaches a
          // pixel centre.
          if (!(stddev >= 0.125 && stddev <= 4)) fail(n, "stddev must be in [0.125, 4] pixels");
        }
        rejectUnused(filterProps, "rfilter type 'gaussian'");
        cam.filter = FilterType::Gaussian;
        cam.filterRadius = float(4 * stddev);
        cam.filterAlpha = float(1 / (2 * stddev * stddev));
      } else {
        fail(child, "unknown or unsupported reconstruction filter type '" + type +
                        "' (supported: tent, box, gaussian)");
      }
    }
  }

  double getIor(PropertySet& props, const char* name, double def) const {
    pugi::xml_node n = props.take(name);
    if (!n) return def;
    requireTag(n, {"float", "integer", "string"});
    double v;
    if (std::string_view(n.name()) == "string") {
      std::string key = toLower(std::string(trim(requireValue(n))));
      auto it = namedIors().find(key);
      if (it == namedIors().end())
        fail(n, std::string("parameter '") + name + "': unknown material '" + requireValue(n) +
                    "' (give a number or a name of Mitsuba's IOR table)");
      v = it->second;
    } else {
      v = number(n, requireValue(n), std::string("parameter '") + name + "'");
    }
    if (!(v > 0)) fail(n, std::string("parameter '") + name + "' must be > 0");
    return v;
  }

  // intIOR and extIOR of a (rough) dielectric.
  void parseDielectricIndex(PropertySet& props, BsdfDescription* b, const std::string& type) {
    b->intIOR = float(getIor(props, "intIOR", 1.5046));
    b->extIOR = float(getIor(props, "extIOR", 1.000277));
    // The description has no slot for tinted glass: accept only Mitsuba's default of 1.
    for (const char* name : {"specularReflectance", "specularTransmittance"}) {
      pugi::xml_node n = props.take(name);
      if (n && !(spectrumOf(n).x == 1 && spectrumOf(n).y == 1 && spectrumOf(n).z == 1))
        fail(n, std::string(name) + " other than 1 is not supported for " + type);
    }
  }

  // The microfacet distribution and its roughness, of roughconductor and roughdielectric.
  void parseRoughness(const pugi::xml_node& node, PropertySet& props, BsdfDescription* b) {
    pugi::xml_node distNode;
    std::string dist = toLower(getString(props, "distribution", "beckmann", &distNode));
    if (dist == "beckmann") {
      b->distribution = MicrofacetDistribution::Beckmann;
    } else if (dist == "ggx") {
      b->distribution = MicrofacetDistribution::GGX;
    } else {
      fail(distNode, "unsupported microfacet distribution '" + dist + "' (beckmann or ggx)");
    }
    pugi::xml_node alphaNode = props.take("alpha");
    pugi::xml_node alphaU = props.take("alphaU"), alphaV = props.take("alphaV");
    double alpha = 0.1;
    if (alphaNode && (alphaU || alphaV)) fail(alphaNode, "give either alpha or alphaU/alphaV");
    auto readAlpha = [&](const pugi::xml_node& n) {
      requireTag(n, {"float", "integer"});
      return number(n, requireValue(n), "parameter '" + paramName(n) + "'");
    };
    if (alphaNode) {
      alpha = readAlpha(alphaNode);
    } else if (alphaU || alphaV) {
      if (!alphaU || !alphaV) fail(alphaU ? alphaU : alphaV, "alphaU and alphaV go together");
      double u = readAlpha(alphaU), v = readAlpha(alphaV);
      if (u != v) fail(alphaU, "anisotropic roughness (alphaU != alphaV) is not supported");
      alpha = u;
    }
    if (!(alpha > 0)) fail(alphaNode ? alphaNode : (alphaU ? alphaU : node), "alpha must be > 0");
    // Below 1e-4 the microfacet distributions lose precision; such a surface is a mirror anyway.
    b->alpha = float(std::max(alpha, 1e-4));
    props.take("sampleVisible");  // a sampling choice, not a look
  }

  // Mitsuba's plastic and roughplastic: a diffuse base under a dielectric coat
  // (bsdfs/coated_diffuse.h's CoatedDiffuseBsdf). The smooth plastic's coat becomes a microfacet
  // coat of alpha 1e-4, which the stability suite shows renders as the smooth one does except that
  // it reflects point lights.
  void parseCoatedDiffuse(const pugi::xml_node& node, PropertySet& props, const std::string& type,
                          BsdfDescription* b) {
    b->type = BsdfDescription::Type::CoatedDiffuse;
    if (type == "roughplastic") {
      parseRoughness(node, props, b);
    } else {
      b->distribution = MicrofacetDistribution::GGX;
      b->alpha = 1e-4f;
      scene_.warnings.push_back(
          baseName_ + ":" + std::to_string(lineOf(node)) +
          ": plastic: its smooth coat is rendered as a microfacet coat of roughness 1e-4 (the same "
          "image, except that point lights leave a tiny highlight)");
    }
    b->intIOR = float(getIor(props, "intIOR", 1.49));  // polypropylene
    b->extIOR = float(getIor(props, "extIOR", 1.000277));
    b->nonlinear = getBoolean(props, "nonlinear", false);
    b->specularReflectance = getSpectrum(props, "specularReflectance", Spectrum(1.0f));
    b->reflectance = getSpectrum(props, "diffuseReflectance", Spectrum(0.5f));
    finishCoatedDiffuse(path_, lineOf(node), type, b);
  }

  // The complex index of refraction of a (rough) conductor, and its reflectance scale.
  void parseConductorIndex(PropertySet& props, BsdfDescription* b) {
    pugi::xml_node materialNode;
    std::string material = getString(props, "material", "Cu", &materialNode);
    if (material == "Cu") {
      b->eta = kCopperEta;
      b->k = kCopperK;
    } else if (toLower(material) == "none") {
      b->eta = Spectrum(0.0f);
      b->k = Spectrum(1.0f);
    } else {
      fail(materialNode, "conductor material '" + material +
                             "' is not supported; give eta and k as <rgb> (or Cu, none)");
    }
    b->eta = getSpectrum(props, "eta", b->eta);
    b->k = getSpectrum(props, "k", b->k);
    b->extEta = float(getIor(props, "extEta", 1.0));
    b->specularReflectance = getSpectrum(props, "specularReflectance", Spectrum(1.0f));
  }

  BsdfDescription parseBsdf(const pugi::xml_node& node) {
    std::string type = node.attribute("type").as_string();
    std::vector<pugi::xml_node> nested;
    PropertySet props = collectProperties(node, &nested);
    BsdfDescription b;
    b.id = node.attribute("id").as_string();
    std::string what = "bsdf type '" + type + "'";
    if (type == "twosided") {
      if (nested.size() != 1)
        fail(node, nested.empty() ? "twosided needs one nested <bsdf>"
                                  : "twosided with more than one nested <bsdf> (different sides) "
                                    "is not supported");
      const pugi::xml_node& inner = nested[0];
      std::string_view tag = inner.name();
      if (tag == "bsdf") {
        b = parseBsdf(inner);
      } else if (tag == "ref") {
        b = scene_.bsdfs[resolveBsdfRef(inner)];
      } else {
        failUnknownElement(inner);
      }
      if (b.type == BsdfDescription::Type::Dielectric ||
          b.type == BsdfDescription::Type::RoughDielectric) {
        // A dielectric's two sides differ by nature (the relative index flips): mirroring the
        // back onto the front would swap reflection and transmission with the wrong index.
        fail(node,
             "twosided cannot wrap a dielectric: a dielectric already has two sides "
             "(Mitsuba refuses this too)");
      }
      b.twoSided = true;
      b.id = node.attribute("id").as_string();
      rejectUnused(props, what);
      return b;
    }
    // Textured parameters: <texture name="reflectance" ...> or <ref name="reflectance" id=.../>.
    // Only a diffuse reflectance may be textured.
    const char* texturable = type == "diffuse"                               ? "reflectance"
                             : (type == "plastic" || type == "roughplastic") ? "diffuseReflectance"
                                                                             : nullptr;
    for (const pugi::xml_node& child : nested) {
      std::string_view tag = child.name();
      if (tag != "texture" && !(tag == "ref" && child.attribute("name"))) failUnknownElement(child);
      const std::string name = child.attribute("name").as_string();
      if (name.empty()) fail(child, "a <" + std::string(tag) + "> in a bsdf needs a name");
      if (!texturable || name != texturable)
        fail(child, "a textured '" + name + "' is not supported for " + what +
                        (texturable ? std::string(" (only its ") + texturable + " may be)" : ""));
      if (props.has(name.c_str()) || b.reflectanceTexture >= 0)
        fail(child, "parameter '" + name + "' given twice");
      b.reflectanceTexture = tag == "ref" ? resolveRef(child, "texture") : parseTexture(child);
    }
    if (type == "diffuse") {
      b.type = BsdfDescription::Type::Diffuse;
      b.reflectance = getSpectrum(props, "reflectance", Spectrum(0.5f));
    } else if (type == "dielectric") {
      b.type = BsdfDescription::Type::Dielectric;
      parseDielectricIndex(props, &b, "dielectric");
    } else if (type == "conductor") {
      b.type = BsdfDescription::Type::Conductor;
      parseConductorIndex(props, &b);
    } else if (type == "roughconductor") {
      b.type = BsdfDescription::Type::RoughConductor;
      parseRoughness(node, props, &b);
      parseConductorIndex(props, &b);
    } else if (type == "roughdielectric") {
      b.type = BsdfDescription::Type::RoughDielectric;
      parseRoughness(node, props, &b);
      parseDielectricIndex(props, &b, "roughdielectric");
      // Equal indices refract nothing: every refraction goes straight through, where the
      // microfacet transmission lobe is singular (its Jacobian's denominator vanishes).
      if (b.intIOR == b.extIOR)
        fail(node,
             "roughdielectric with intIOR equal to extIOR does not refract; leave the surface out");
    } else if (type == "plastic" || type == "roughplastic") {
      parseCoatedDiffuse(node, props, type, &b);
    } else {
      fail(node, "unknown or unsupported bsdf type '" + type +
                     "' (supported: diffuse, twosided, dielectric, roughdielectric, conductor, "
                     "roughconductor, plastic, roughplastic)");
    }
    rejectUnused(props, what);
    return b;
  }

  // <texture type="bitmap">: an image looked up bilinearly at the surface's (u, v), scaled and
  // offset. Mitsuba's row v = 0 is the image's top; the description's (t = 0 at the bottom row)
  // gets there because every Mitsuba shape's texture coordinates enter it as (u, 1 - v) (see
  // mitsubaUv), and this mapping is written for those: t = vscale v' + (1 - vscale - voffset).
  int parseTexture(const pugi::xml_node& node) {
    std::string type = node.attribute("type").as_string();
    if (type != "bitmap") fail(node, "unsupported texture type '" + type + "' (bitmap only)");
    std::vector<pugi::xml_node> nested;
    PropertySet props = collectProperties(node, &nested);
    for (const pugi::xml_node& child : nested) failUnknownElement(child);
    pugi::xml_node fileNode;
    const std::string filename = getString(props, "filename", "", &fileNode);
    if (trim(filename).empty()) fail(fileNode ? fileNode : node, "bitmap texture has no filename");
    TextureDescription t;
    t.type = TextureDescription::Type::Image;
    const std::string wrap = getString(props, "wrapMode", "repeat");
    const std::string wrapU = getString(props, "wrapModeU", wrap);
    const std::string wrapV = getString(props, "wrapModeV", wrap);
    if (wrapU != wrapV) fail(node, "different wrap modes in u and v are not supported");
    if (wrapU == "repeat") {
      t.wrap = TextureWrap::Repeat;
    } else if (wrapU == "clamp") {
      t.wrap = TextureWrap::Clamp;
    } else if (wrapU == "zero" || wrapU == "black") {
      t.wrap = TextureWrap::Black;
    } else {
      fail(node, "texture wrap mode '" + wrapU + "' is not supported (repeat, clamp, zero)");
    }
    TextureEncoding encoding = TextureEncoding::Automatic;
    if (pugi::xml_node g = props.take("gamma")) {
      requireTag(g, {"float", "integer"});
      const double gamma = number(g, requireValue(g), "parameter 'gamma'");
      if (gamma == -1) {
        encoding = TextureEncoding::SRGB;
      } else if (gamma == 1) {
        encoding = TextureEncoding::Linear;
      } else if (gamma != 0) {
        fail(g, "texture gamma " + std::string(requireValue(g)) +
                    " is not supported (-1 for sRGB, 1 for linear, or leave it out)");
      }
    }
    if (props.has("channel"))
      fail(props.take("channel"), "single-channel textures are not supported");
    // EWA and trilinear filtering average the texture over a pixel's footprint; here the pixel
    // filter and the samples do that.
    const std::string filter = getString(props, "filterType", "ewa");
    if (filter != "ewa" && filter != "trilinear" && filter != "nearest")
      fail(node, "unknown texture filterType '" + filter + "' (ewa, trilinear, nearest)");
    getNumber(props, "maxAnisotropy", 20);
    getBoolean(props, "cache", false);
    const double uvScale = getNumber(props, "uvscale", 1);
    const double uScale = getNumber(props, "uscale", uvScale);
    const double vScale = getNumber(props, "vscale", uvScale);
    const double uOffset = getNumber(props, "uoffset", 0);
    const double vOffset = getNumber(props, "voffset", 0);
    rejectUnused(props, "texture type 'bitmap'");
    t.uScale = float(uScale);
    t.uOffset = float(uOffset);
    t.vScale = float(vScale);
    t.vOffset = float(1 - vScale - vOffset);
    t.image = images_.load(dir_, filename, encoding, path_, lineOf(fileNode));
    t.origin = baseName_ + ":" + std::to_string(lineOf(node)) + " (bitmap " + filename + ")";
    scene_.textures.push_back(std::move(t));
    return int(scene_.textures.size()) - 1;
  }

  int addBsdf(const BsdfDescription& b) {
    scene_.bsdfs.push_back(b);
    return int(scene_.bsdfs.size()) - 1;
  }

  Spectrum parseAreaEmitter(const pugi::xml_node& node) {
    std::string type = node.attribute("type").as_string();
    if (type != "area")
      fail(node, "unsupported emitter type '" + type + "' inside a shape (only area)");
    PropertySet props = collectProperties(node, nullptr);
    Spectrum radiance = getSpectrum(props, "radiance", Spectrum(1.0f));
    props.take("samplingWeight");  // light selection is the farm's own business
    rejectUnused(props, "emitter type 'area'");
    return radiance;
  }

  double getNumber(PropertySet& props, const char* name, double def) const {
    pugi::xml_node n = props.take(name);
    if (!n) return def;
    requireTag(n, {"float", "integer"});
    return number(n, requireValue(n), std::string("parameter '") + name + "'");
  }

  // <emitter type="point"> and <emitter type="spot">: intensity from a position (point's
  // "position", or toWorld's origin); a spot looks down its toWorld's +z, fully bright within
  // beamWidth and dark beyond cutoffAngle (degrees).
  void parsePointEmitter(const pugi::xml_node& node, const std::string& type) {
    PropertySet props = collectProperties(node, nullptr);
    props.take("samplingWeight");
    PointLightDescription light;
    light.intensity = getSpectrum(props, "intensity", Spectrum(1.0f));
    Matrix4 toWorld = Matrix4::identity();
    if (pugi::xml_node t = props.take("toWorld")) toWorld = transformOf(t);
    light.position = toWorld.applyPoint(getPoint(props, "position", Vec3f(0.0f)));
    if (type == "spot") {
      const double cutoff = getNumber(props, "cutoffAngle", 20);
      const double beam = getNumber(props, "beamWidth", cutoff * 3 / 4);
      if (!(cutoff > 0 && cutoff <= 90)) fail(node, "spot cutoffAngle must be in (0, 90] degrees");
      if (!(beam >= 0 && beam <= cutoff)) fail(node, "spot beamWidth must be in [0, cutoffAngle]");
      const Vec3f axis = toWorld.applyVector(Vec3f(0, 0, 1));
      if (!(length(axis) > 0) || !isFinite(axis)) fail(node, "spot toWorld is singular");
      light.spot = true;
      light.direction = normalize(axis);
      light.cosTotalWidth = float(std::cos(cutoff * M_PI / 180));
      light.cosFalloffStart = float(std::cos(beam * M_PI / 180));
      light.falloff = PointLightDescription::Falloff::MitsubaLinearAngle;
    }
    rejectUnused(props, "emitter type '" + type + "'");
    if (!isFinite(light.position)) fail(node, type + " emitter: its position is not finite");
    light.origin = fs::path(path_).filename().string() + ":" + std::to_string(lineOf(node)) + " (" +
                   type + ")";
    scene_.pointLights.push_back(light);
  }

  // <emitter> at the top level: the environment (constant, envmap) or a point light.
  void parseTopLevelEmitter(const pugi::xml_node& node) {
    std::string type = node.attribute("type").as_string();
    if (type == "area") fail(node, "an area <emitter> must be nested in the <shape> that emits");
    if (type == "point" || type == "spot") return parsePointEmitter(node, type);
    if (type != "constant" && type != "envmap")
      fail(node, "unsupported emitter type '" + type +
                     "' (area emitters nested in shapes, constant, envmap, point and spot)");
    if (scene_.environment.present)
      fail(node, "more than one environment emitter (constant or envmap)");
    PropertySet props = collectProperties(node, nullptr);
    props.take("samplingWeight");  // light selection is the farm's own business
    Spectrum scale(1.0f);
    std::string filename;
    Matrix4 toWorld = Matrix4::identity();
    if (type == "constant") {
      scale = getSpectrum(props, "radiance", Spectrum(1.0f));
    } else {
      pugi::xml_node where;
      filename = getString(props, "filename", "", &where);
      if (filename.empty()) fail(node, "envmap has no filename");
      scale = getSpectrum(props, "scale", Spectrum(1.0f));
      if (pugi::xml_node t = props.take("toWorld")) toWorld = transformOf(t);
      props.take("cache");  // Mitsuba's MIP map cache: nothing to cache here
    }
    rejectUnused(props, "emitter type '" + type + "'");
    // Mitsuba's lat-long frame has y up and u = atan2(x, -z) / 2 pi; the description's is
    // pbrt's (z up, u = atan2(y, x) / 2 pi): local Mitsuba (x, y, z) = (y', z', -x') of pbrt's.
    Matrix4 mitsubaFromPbrt;
    mitsubaFromPbrt.m[0] = {0, 1, 0, 0};
    mitsubaFromPbrt.m[1] = {0, 0, 1, 0};
    mitsubaFromPbrt.m[2] = {-1, 0, 0, 0};
    mitsubaFromPbrt.m[3] = {0, 0, 0, 1};
    scene_.environment = makeEnvironment(dir_, path_, lineOf(node), scale,
                                         toWorld * mitsubaFromPbrt, filename, false);
  }

  // <medium type="homogeneous">: sigmaA and sigmaS, or sigmaT and albedo, times scale.
  // <medium type="heterogeneous">: sigma_t = scale times a density volume (a gridvolume file or
  // a constvolume), a constant albedo. Either with a <phase> (isotropic or hg). Returns its
  // index in scene_.media.
  int parseMedium(const pugi::xml_node& node) {
    checkAttributes(node, {"type", "id", "name"});
    const std::string type = node.attribute("type").as_string();
    if (type != "homogeneous" && type != "heterogeneous")
      fail(node, "unknown or unsupported medium type '" + type +
                     "' (homogeneous and heterogeneous only)");
    std::vector<pugi::xml_node> nested;
    PropertySet props = collectProperties(node, &nested);
    MediumDescription m;
    m.id = node.attribute("id").as_string();
    m.origin = baseName_ + ":" + std::to_string(lineOf(node)) + " (" + type + ")";
    if (pugi::xml_node n = props.take("material"))
      fail(n,
           "named medium materials (measured coefficients) are not supported: give sigmaA "
           "and sigmaS");
    const double scale = getNumber(props, "scale", getNumber(props, "densityMultiplier", 1.0));
    if (!(scale >= 0) || !std::isfinite(scale)) fail(node, "a medium's scale must be >= 0");
    bool sawPhase = false;
    pugi::xml_node densityNode, albedoNode;
    for (const pugi::xml_node& child : nested) {
      const std::string_view tag = child.name();
      if (tag == "phase") {
        if (sawPhase) fail(child, "a medium takes one phase function");
        sawPhase = true;
        m.g = parsePhase(child);
      } else if (tag == "volume" && type == "heterogeneous") {
        const std::string name = child.attribute("name").as_string();
        if (name != "density" && name != "albedo")
          fail(child,
               "a heterogeneous medium's volumes are 'density' and 'albedo', not '" + name + "'");
        (name == "density" ? densityNode : albedoNode) = child;
      } else {
        failUnknownElement(child);
      }
    }
    if (type == "homogeneous") {
      const bool coefficients = props.has("sigmaA") || props.has("sigmaS");
      const bool extinction = props.has("sigmaT") || props.has("albedo");
      if (coefficients && extinction)
        fail(node, "give sigmaA and sigmaS, or sigmaT and albedo, not both");
      if (extinction) {
        const Spectrum sigmaT = getSpectrum(props, "sigmaT", Spectrum(1.0f));
        const Spectrum albedo = getSpectrum(props, "albedo", Spectrum(1.0f));
        m.sigmaS = sigmaT * albedo;
        m.sigmaA = sigmaT - m.sigmaS;
      } else {
        m.sigmaA = getSpectrum(props, "sigmaA", Spectrum(1.0f));
        m.sigmaS = getSpectrum(props, "sigmaS", Spectrum(1.0f));
      }
      m.sigmaA *= float(scale);
      m.sigmaS *= float(scale);
    } else {
      props.take("method");    // Woodcock tracking is what the farm does anyway
      props.take("stepSize");  // ray marching's step: the farm's estimators need none
      if (!densityNode) fail(node, "a heterogeneous medium needs a <volume name=\"density\">");
      Spectrum albedo(1.0f);
      if (albedoNode) albedo = constantVolume(albedoNode, "albedo");
      const float constant = parseDensityVolume(densityNode, &m);
      // Mitsuba: sigma_t = scale * density, sigma_s = sigma_t * albedo.
      m.sigmaS = albedo * float(scale * constant);
      m.sigmaA = Spectrum(float(scale * constant)) - m.sigmaS;
    }
    rejectUnused(props, "medium type '" + type + "'");
    const std::string problem = mediumProblem(m);
    if (!problem.empty()) fail(node, problem);
    scene_.media.push_back(std::move(m));
    return int(scene_.media.size()) - 1;
  }

  // <phase type="isotropic"/> or <phase type="hg"><float name="g" .../></phase>: the g of a
  // Henyey-Greenstein phase function (0: isotropic).
  double parsePhase(const pugi::xml_node& node) {
    const std::string type = node.attribute("type").as_string();
    PropertySet props = collectProperties(node, nullptr);
    double g = 0;
    if (type == "hg") {
      g = getNumber(props, "g", 0.8);
      if (!(std::fabs(g) < 1)) fail(node, "the Henyey-Greenstein g must lie in (-1, 1)");
    } else if (type != "isotropic") {
      fail(node, "unknown or unsupported phase function '" + type + "' (isotropic and hg only)");
    }
    rejectUnused(props, "phase function '" + type + "'");
    return g;
  }

  // A constvolume's value (the albedo; a grid of albedos is not supported).
  Spectrum constantVolume(const pugi::xml_node& node, const std::string& what) {
    const std::string type = node.attribute("type").as_string();
    if (type != "constvolume")
      fail(node, "the " + what + " volume must be a constvolume (not '" + type + "')");
    PropertySet props = collectProperties(node, nullptr);
    const Spectrum v = getSpectrum(props, "value", Spectrum(1.0f));
    rejectUnused(props, "volume type 'constvolume'");
    return v;
  }

  // The density: a constvolume (the same everywhere: *m becomes homogeneous, and the value is
  // returned as a factor of sigma_t) or a gridvolume file, whose samples span its bounding box
  // corner to corner, placed in the world by its toWorld (returns 1).
  float parseDensityVolume(const pugi::xml_node& node, MediumDescription* m) {
    const std::string type = node.attribute("type").as_string();
    if (type == "constvolume") {
      const Spectrum v = constantVolume(node, "density");
      if (v.x != v.y || v.x != v.z) fail(node, "a density must be a single number");
      m->type = MediumDescription::Type::Homogeneous;
      return v.x;
    }
    m->type = MediumDescription::Type::Grid;
    if (type != "gridvolume")
      fail(node, "unknown or unsupported volume type '" + type + "' (gridvolume, constvolume)");
    PropertySet props = collectProperties(node, nullptr);
    pugi::xml_node fileNode;
    const std::string filename = getString(props, "filename", "", &fileNode);
    if (!fileNode || trim(filename).empty()) fail(node, "a gridvolume needs a filename");
    Matrix4 toWorld = Matrix4::identity();
    if (pugi::xml_node t = props.take("toWorld")) toWorld = transformOf(t);
    props.take("sendData");  // a network-rendering switch
    // The farm's extension: an OpenVDB file's float grid (gridName, or the first one).
    const bool vdb = filename.size() > 4 && toLower(filename.substr(filename.size() - 4)) == ".vdb";
    pugi::xml_node gridNameNode;
    const std::string gridName = vdb ? getString(props, "gridName", "", &gridNameNode) : "";
    rejectUnused(props, "volume type 'gridvolume'");
    const Matrix4 worldToVolume = toWorld.inverse();
    if (!worldToVolume.isFinite()) fail(node, "the gridvolume's toWorld is singular");
    const std::filesystem::path file =
        sceneFilePath(dir_, filename, "volume file", path_, lineOf(fileNode));
    std::string problem;
    if (vdb) {
      if (!readVdbDensity(file, gridName, m, &problem)) fail(fileNode, filename + ": " + problem);
      m->worldToGrid = m->worldToGrid * worldToVolume;
      return 1;
    }
    const std::string bytes = readSceneFile(file, "volume file", path_, lineOf(fileNode));
    GridVolume volume;
    if (!decodeGridVolume(bytes, &volume, &problem)) fail(fileNode, filename + ": " + problem);
    m->nx = volume.nx, m->ny = volume.ny, m->nz = volume.nz;
    m->density = std::move(volume.values);
    m->cellCentred = false;
    const Vec3f extent = volume.boundsMax - volume.boundsMin;
    m->worldToGrid = Matrix4::scale(Vec3f(1 / extent.x, 1 / extent.y, 1 / extent.z)) *
                     Matrix4::translate(-volume.boundsMin) * worldToVolume;
    return 1;
  }

  void parseShape(const pugi::xml_node& node) {
    std::string type = node.attribute("type").as_string();
    if (type != "rectangle" && type != "cube" && type != "sphere" && type != "obj" &&
        type != "ply" && type != "serialized")
      fail(node, "unknown or unsupported shape type '" + type +
                     "' (supported: rectangle, cube, sphere, obj, ply, serialized)");
    std::vector<pugi::xml_node> nested;
    PropertySet props = collectProperties(node, &nested);
    ShapeDescription shape;
    std::string origin = baseName_ + ":" + std::to_string(lineOf(node)) + " (" + type;

    // Material and emission first: they need no geometry.
    int bsdf = -1;
    pugi::xml_node emitterNode;
    for (const pugi::xml_node& child : nested) {
      std::string_view tag = child.name();
      const std::string_view name = child.attribute("name").value();
      if ((tag == "medium" || tag == "ref") && (name == "interior" || name == "exterior")) {
        // The media on either side: <medium name="interior" ...> or <ref name="interior" .../>.
        int& side = name == "interior" ? shape.interiorMedium : shape.exteriorMedium;
        if (side >= 0) fail(child, "shape has more than one " + std::string(name) + " medium");
        side = tag == "ref" ? resolveRef(child, "medium") : parseMedium(child);
        shape.hasMediumInterface = true;
      } else if (tag == "bsdf" || tag == "ref") {
        if (bsdf >= 0) fail(child, "shape has more than one bsdf");
        if (tag == "ref") {
          bsdf = resolveBsdfRef(child);
        } else {
          bsdf = addBsdf(parseBsdf(child));
          registerId(child, "bsdf", bsdf);
        }
      } else if (tag == "emitter") {
        if (emitterNode) fail(child, "shape has more than one emitter");
        emitterNode = child;
        shape.radiance = parseAreaEmitter(child);
        // A black emitter emits nothing: treat it as a plain surface, so that no light sampling
        // ever has to pick a light of zero power.
        shape.isEmitter = !isBlack(shape.radiance);
      } else {
        failUnknownElement(child);
      }
    }
    if (bsdf < 0 && shape.hasMediumInterface) {
      // Mitsuba's medium transition: a shape with media and no BSDF only bounds them.
      if (shape.isEmitter)
        fail(node, "an emitting shape that bounds a medium needs a BSDF (its surface scatters)");
      shape.nullBoundary = true;
    } else if (bsdf < 0) {
      // Mitsuba gives a shape without a material a diffuse one of reflectance 0.5, and an
      // emitter without one an absorbing one (its Shape::configure).
      BsdfDescription def;
      def.type = BsdfDescription::Type::Diffuse;
      def.reflectance = Spectrum(emitterNode ? 0.0f : 0.5f);
      bsdf = addBsdf(def);
    }
    shape.bsdf = bsdf;
    const bool textured = bsdf >= 0 && scene_.bsdfs[size_t(bsdf)].reflectanceTexture >= 0;
    if (textured && (type == "sphere" || type == "cube"))
      fail(node, "a textured " + type +
                     " is not supported (texture coordinates come from meshes "
                     "and rectangles only)");

    Matrix4 toWorld = Matrix4::identity();
    pugi::xml_node transformNode = props.take("toWorld");
    if (transformNode) toWorld = transformOf(transformNode);
    bool flip = getBoolean(props, "flipNormals", false);
    std::string what = "shape type '" + type + "'";

    if (type == "sphere") {
      shape.type = ShapeDescription::Type::Sphere;
      Vec3f center = getPoint(props, "center", Vec3f(0.0f));
      pugi::xml_node radiusNode = props.take("radius");
      double radius = 1.0;
      if (radiusNode) {
        requireTag(radiusNode, {"float", "integer"});
        radius = number(radiusNode, requireValue(radiusNode), "parameter 'radius'");
        if (!(radius > 0)) fail(radiusNode, "sphere radius must be > 0");
      }
      shape.center = toWorld.applyPoint(center);
      shape.radius = float(radius * similarityScale(transformNode ? transformNode : node, toWorld));
      if (!(shape.radius > 0) || !std::isfinite(shape.radius) || !isFinite(shape.center))
        fail(node, "sphere has a degenerate world-space radius or center");
      shape.flipNormals = flip;
      rejectUnused(props, what);
      shape.origin = origin + ")";
      scene_.shapes.push_back(std::move(shape));
      registerId(node, "shape", int(scene_.shapes.size()) - 1);
      return;
    }

    shape.type = ShapeDescription::Type::TriangleMesh;
    // A mirroring transform turns counter-clockwise triangles clockwise; generated shapes keep
    // their outward orientation by reversing the winding then.
    bool mirrored = determinant3(toWorld) < 0;
    if (type == "rectangle") {
      rejectUnused(props, what);
      makeRectangle(toWorld, mirrored != flip, flip, &shape);
      shape.origin = origin + ")";
    } else if (type == "cube") {
      rejectUnused(props, what);
      makeCube(toWorld, mirrored != flip, &shape);
      shape.origin = origin + ")";
    } else {
      pugi::xml_node fileNode;
      std::string filename = getString(props, "filename", "", &fileNode);
      if (!fileNode) fail(node, type + " shape without a filename parameter");
      if (trim(filename).empty()) fail(fileNode, "empty " + type + " filename");
      bool faceNormals = getBoolean(props, "faceNormals", false);
      bool flipTexCoords = true;
      long long shapeIndex = 0;
      if (type == "obj") {
        flipTexCoords = getBoolean(props, "flipTexCoords", true);
        getBoolean(props, "collapse", false);  // we always merge an OBJ's groups into one mesh
      } else if (type == "ply") {
        getBoolean(props, "srgb", true);  // vertex colours: no texture reads them
      } else if (pugi::xml_node n = props.take("shapeIndex")) {
        shapeIndex = getIntegerFrom(n, "shapeIndex");
        if (shapeIndex < 0 || shapeIndex > std::numeric_limits<int>::max())
          fail(n, "shapeIndex must be >= 0");
      }
      if (pugi::xml_node n = props.take("maxSmoothAngle"))
        fail(n, "maxSmoothAngle (normals rebuilt at creases) is not supported");
      rejectUnused(props, what);
      if (type == "obj") {
        loadObj(fileNode, filename, toWorld, faceNormals, flip, flipTexCoords, &shape);
      } else if (type == "ply") {
        loadPly(fileNode, filename, toWorld, faceNormals, flip, &shape);
      } else {
        loadSerialized(fileNode, filename, int(shapeIndex), toWorld, faceNormals, flip, &shape);
      }
      if (textured && shape.uvs.empty())
        fail(fileNode,
             type + " '" + filename + "' has a textured material but no texture coordinates");
      shape.origin = origin + " " + filename + ")";
    }
    scene_.shapes.push_back(std::move(shape));
    registerId(node, "shape", int(scene_.shapes.size()) - 1);
  }

  // The uniform scale factor of a rotation-scale-translation matrix; spheres stay analytic, so an
  // ellipsoid-making transform is refused.
  double similarityScale(const pugi::xml_node& node, const Matrix4& t) const {
    double s;
    switch (similarityOf(t, &s)) {
      case Similarity::NonUniformScale:
        fail(node, "sphere toWorld has a non-uniform scale (the sphere would be an ellipsoid)");
      case Similarity::Shear:
        fail(node, "sphere toWorld has a shear");
      case Similarity::Uniform:
        break;
    }
    return s;
  }

  // Texture coordinates as the description has them: Mitsuba looks up row v of an image from
  // its top (its mipmap's evalBilinear), the description from its bottom.
  static Vec2f mitsubaUv(const Vec2f& uv) { return Vec2f(uv.x, 1 - uv.y); }

  static void addQuad(ShapeDescription* shape, const Vec3f corners[4], bool reverse) {
    uint32_t base = uint32_t(shape->positions.size());
    for (int i = 0; i < 4; ++i) shape->positions.push_back(corners[i]);
    const uint32_t ccw[6] = {0, 1, 2, 2, 3, 0}, cw[6] = {0, 2, 1, 2, 0, 3};
    for (uint32_t i : reverse ? cw : ccw) shape->indices.push_back(base + i);
  }

  static void makeRectangle(const Matrix4& toWorld, bool reverse, bool flip,
                            ShapeDescription* shape) {
    const Vec3f local[4] = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    Vec3f world[4];
    for (int i = 0; i < 4; ++i) world[i] = toWorld.applyPoint(local[i]);
    addQuad(shape, world, reverse);
    // The plane's normal through the inverse transpose, as Mitsuba's analytic rectangle has it.
    Vec3f n = normalize(toWorld.inverse().transpose().applyVector(Vec3f(0, 0, 1)));
    if (flip) n = -n;
    shape->normals.assign(4, n);
    // Mitsuba's (x + 1, y + 1) / 2 at the corners above, as mitsubaUv gives them.
    const Vec2f mitsuba[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (const Vec2f& uv : mitsuba) shape->uvs.push_back(mitsubaUv(uv));
    shape->faceNormals = false;
  }

  static void makeCube(const Matrix4& toWorld, bool reverse, ShapeDescription* shape) {
    // Each face from its outward normal n and tangents u, v with u x v = n, so that the corners
    // c - u - v, c + u - v, c + u + v, c - u + v run counter-clockwise seen from outside.
    for (int axis = 0; axis < 3; ++axis) {
      for (float sign : {1.0f, -1.0f}) {
        Vec3f n(0.0f), u(0.0f);
        n[axis] = sign;
        u[(axis + 1) % 3] = 1.0f;
        Vec3f v = cross(n, u);
        Vec3f corners[4] = {n - u - v, n + u - v, n + u + v, n - u + v};
        for (Vec3f& c : corners) c = toWorld.applyPoint(c);
        addQuad(shape, corners, reverse);
      }
    }
    shape->faceNormals = true;
  }

  // flipTexCoords: Mitsuba's default, v -> 1 - v, for OBJ files whose v runs up the image.
  void loadObj(const pugi::xml_node& fileNode, const std::string& filename, const Matrix4& toWorld,
               bool faceNormals, bool flip, bool flipTexCoords, ShapeDescription* shape) {
    const fs::path objPath = sceneFilePath(dir_, filename, "mesh file", path_, lineOf(fileNode));

    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    // From memory, with no material library: tinyobj would open whatever file an `mtllib` line
    // names (outside the scene's folder, or /dev/zero), and materials come from the XML anyway.
    tinyobj::ObjReader reader;
    if (!reader.ParseFromString(
            readSceneFile(objPath, "OBJ '" + filename + "'", path_, lineOf(fileNode)), "",
            config)) {
      std::string err = reader.Error();
      while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
      fail(fileNode,
           "cannot parse OBJ '" + filename + "': " + (err.empty() ? "unknown error" : err));
    }
    const tinyobj::attrib_t& attrib = reader.GetAttrib();
    const size_t numPositions = attrib.vertices.size() / 3;
    const size_t numNormals = attrib.normals.size() / 3;
    const size_t numTexcoords = attrib.texcoords.size() / 2;

    // Corners of all groups, in order; the file's normals only if every corner has one.
    std::vector<tinyobj::index_t> corners;
    for (const tinyobj::shape_t& s : reader.GetShapes()) {
      size_t offset = 0;
      for (unsigned char fv : s.mesh.num_face_vertices) {
        if (fv == 3)
          for (int k = 0; k < 3; ++k) corners.push_back(s.mesh.indices[offset + k]);
        offset += fv;
      }
    }
    if (corners.empty()) fail(fileNode, "OBJ '" + filename + "' contains no triangles");
    bool fileNormals = !faceNormals && numNormals > 0;
    bool fileTexcoords = numTexcoords > 0;
    for (const tinyobj::index_t& c : corners) {
      if (c.vertex_index < 0 || size_t(c.vertex_index) >= numPositions)
        fail(fileNode, "OBJ '" + filename + "' has a face with an invalid vertex index");
      if (c.normal_index < 0 || size_t(c.normal_index) >= numNormals) fileNormals = false;
      if (c.texcoord_index < 0 || size_t(c.texcoord_index) >= numTexcoords) fileTexcoords = false;
    }

    // One vertex per distinct (position, normal, texture coordinate), as the file shares them.
    struct Source {
      int position, normal, texcoord;  // -1: none
      bool operator<(const Source& o) const {
        return std::tie(position, normal, texcoord) < std::tie(o.position, o.normal, o.texcoord);
      }
    };
    std::map<Source, uint32_t> vertexOf;
    std::vector<Source> sources;
    shape->indices.reserve(corners.size());
    for (const tinyobj::index_t& c : corners) {
      const Source key{c.vertex_index, fileNormals ? c.normal_index : -1,
                       fileTexcoords ? c.texcoord_index : -1};
      auto [it, inserted] = vertexOf.emplace(key, uint32_t(sources.size()));
      if (inserted) sources.push_back(key);
      shape->indices.push_back(it->second);
    }

    std::vector<Vec3f> positions(sources.size()), normals;
    std::vector<Vec2f> uvs;
    for (size_t i = 0; i < sources.size(); ++i) {
      const float* p = &attrib.vertices[3 * size_t(sources[i].position)];
      positions[i] = Vec3f(p[0], p[1], p[2]);
    }
    if (fileNormals) {
      normals.resize(sources.size());
      for (size_t i = 0; i < sources.size(); ++i) {
        const float* n = &attrib.normals[3 * size_t(sources[i].normal)];
        normals[i] = Vec3f(n[0], n[1], n[2]);
      }
    }
    if (fileTexcoords) {
      uvs.resize(sources.size());
      for (size_t i = 0; i < sources.size(); ++i) {
        const float* t = &attrib.texcoords[2 * size_t(sources[i].texcoord)];
        const Vec2f uv(t[0], flipTexCoords ? 1 - t[1] : t[1]);
        uvs[i] = mitsubaUv(uv);
      }
    }
    finishMesh(path_, lineOf(fileNode), "OBJ '" + filename + "'", toWorld, faceNormals, flip,
               std::move(positions), std::move(normals), std::move(uvs), shape, &scene_.warnings);
  }

  // A PLY mesh through Open Asset Import Library (ply_reader.h).
  void loadPly(const pugi::xml_node& fileNode, const std::string& filename, const Matrix4& toWorld,
               bool faceNormals, bool flip, ShapeDescription* shape) {
    const std::string bytes =
        readSceneFile(sceneFilePath(dir_, filename, "mesh file", path_, lineOf(fileNode)),
                      "PLY '" + filename + "'", path_, lineOf(fileNode));
    PlyMesh mesh;
    try {
      mesh = parsePly(bytes);
    } catch (const std::exception& e) {
      fail(fileNode, "cannot read PLY '" + filename + "': " + e.what());
    }
    shape->indices = std::move(mesh.indices);
    for (Vec2f& uv : mesh.uvs) uv = mitsubaUv(uv);
    finishMesh(path_, lineOf(fileNode), "PLY '" + filename + "'", toWorld, faceNormals, flip,
               std::move(mesh.positions), std::move(mesh.normals), std::move(mesh.uvs), shape,
               &scene_.warnings);
  }

  // One mesh of a Mitsuba serialized file (serialized_reader.h); the file's face-normal flag
  // acts as faceNormals does.
  void loadSerialized(const pugi::xml_node& fileNode, const std::string& filename, int shapeIndex,
                      const Matrix4& toWorld, bool faceNormals, bool flip,
                      ShapeDescription* shape) {
    const std::string bytes =
        readSceneFile(sceneFilePath(dir_, filename, "mesh file", path_, lineOf(fileNode)),
                      "serialized mesh '" + filename + "'", path_, lineOf(fileNode));
    SerializedMesh mesh;
    try {
      mesh = parseSerialized(bytes, shapeIndex, kMaxMeshElements);
    } catch (const std::exception& e) {
      fail(fileNode, "cannot read serialized mesh '" + filename + "': " + e.what());
    }
    shape->indices = std::move(mesh.indices);
    for (Vec2f& uv : mesh.uvs) uv = mitsubaUv(uv);
    finishMesh(path_, lineOf(fileNode), "serialized mesh '" + filename + "'", toWorld,
               faceNormals || mesh.faceNormals, flip, std::move(mesh.positions),
               std::move(mesh.normals), std::move(mesh.uvs), shape, &scene_.warnings);
  }

  static constexpr size_t kMaxMeshElements = size_t(1) << 28;  // vertices + triangle corners

  std::string path_;
  fs::path dir_;
  std::string baseName_;
  std::string text_;
  std::vector<size_t> newlines_;
  pugi::xml_document doc_;
  SceneDescription scene_;
  std::map<std::string, IdEntry> ids_;
  std::map<std::string, int> declaredIds_;  // id -> line, over the whole document
  TextureImageCache images_;
};

}  // namespace

SceneDescription loadMitsubaScene(const std::string& path) {
  return MitsubaLoader(path).load();
}

}  // namespace farm
