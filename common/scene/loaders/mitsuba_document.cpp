#include "common/scene/loaders/mitsuba_document.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>

#include "common/scene/loaders/scene_files.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr int kMaxDepth = 64;  // elements nested within one another

float srgbToLinear(double v) {
  return float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
}

}  // namespace

std::string toLower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

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

MitsubaDocument::MitsubaDocument(const std::string& path) : path_(path) {
  text_ = readSceneText(path_);
  for (size_t i = 0; i < text_.size(); ++i)
    if (text_[i] == '\n') newlines_.push_back(i);
  dir_ = fs::path(path_).parent_path();
  baseName_ = fs::path(path_).filename().string();
  // From our own buffer so that offsets (and so line numbers) refer to the file's bytes.
  pugi::xml_parse_result r =
      doc_.load_buffer(text_.data(), text_.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!r)
    throw SceneLoadError(path_, lineOfOffset(r.offset),
                         std::string("malformed XML: ") + r.description());
  pugi::xml_node root = doc_.document_element();
  if (std::string_view(root.name()) != "scene")
    fail(root, "the root element must be <scene>, not <" + std::string(root.name()) + ">");
  checkVersion(root);
  collectDeclaredIds(root);
}

std::string MitsubaDocument::origin(const pugi::xml_node& node) const {
  return baseName_ + ":" + std::to_string(lineOf(node));
}

int MitsubaDocument::lineOfOffset(ptrdiff_t offset) const {
  if (offset < 0) return 0;
  auto it = std::upper_bound(newlines_.begin(), newlines_.end(), size_t(offset));
  return int(it - newlines_.begin()) + 1;
}

void MitsubaDocument::fail(const pugi::xml_node& node, const std::string& problem) const {
  throw SceneLoadError(path_, node ? lineOf(node) : 0, problem);
}

void MitsubaDocument::failUnknownElement(const pugi::xml_node& node) const {
  static const char* const kKnownButUnsupported[] = {"medium", "phase",   "subsurface", "include",
                                                     "alias",  "default", "volume"};
  std::string tag = node.name();
  for (const char* t : kKnownButUnsupported)
    if (tag == t) fail(node, "<" + tag + "> is not supported here");
  fail(node, "unknown element <" + tag + ">");
}

void MitsubaDocument::checkVersion(const pugi::xml_node& root) const {
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
void MitsubaDocument::collectDeclaredIds(const pugi::xml_node& root) {
  struct Walker : pugi::xml_tree_walker {
    const MitsubaDocument* document;
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
        ids->emplace(id.value(), document->lineOf(node));
      return true;
    }
  } walker;
  walker.document = this;
  walker.ids = &declaredIds_;
  pugi::xml_node start = root;
  start.traverse(walker);
  if (walker.tooDeep) fail(walker.tooDeep, "elements nested too deeply");
}

void MitsubaDocument::registerId(const pugi::xml_node& node, const std::string& kind, int index) {
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

int MitsubaDocument::resolveRef(const pugi::xml_node& ref, const std::string& kind) const {
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

const char* MitsubaDocument::requireValue(const pugi::xml_node& n) const {
  pugi::xml_attribute v = n.attribute("value");
  if (!v)
    fail(n, "<" + std::string(n.name()) + " name=\"" + std::string(n.attribute("name").value()) +
                "\"> has no value attribute");
  return v.value();
}

void MitsubaDocument::requireTag(const pugi::xml_node& n,
                                 std::initializer_list<const char*> tags) const {
  std::string allowed;
  for (const char* t : tags) {
    if (std::string_view(n.name()) == t) return;
    if (!allowed.empty()) allowed += " or ";
    allowed += std::string("<") + t + ">";
  }
  fail(n, "parameter '" + std::string(n.attribute("name").value()) + "' must be " + allowed +
              ", not <" + n.name() + ">");
}

double MitsubaDocument::number(const pugi::xml_node& n, std::string_view text,
                               const std::string& what) const {
  double v;
  if (!parseFiniteDouble(text, &v))
    fail(n, what + ": '" + std::string(text) + "' is not a finite number");
  // Everything ends up in float (positions, colors, angles): it must stay finite there too.
  if (std::fabs(v) > double(std::numeric_limits<float>::max()))
    fail(n, what + ": '" + std::string(text) + "' is out of range");
  return v;
}

long long MitsubaDocument::integer(const pugi::xml_node& n, const char* name) const {
  requireTag(n, {"integer"});
  long long v;
  if (!parseInt(requireValue(n), &v))
    fail(n, std::string("parameter '") + name + "': '" + requireValue(n) + "' is not an integer");
  return v;
}

Spectrum MitsubaDocument::spectrumOf(const pugi::xml_node& n) const {
  std::string what = "parameter '" + std::string(n.attribute("name").value()) + "'";
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

Vec3f MitsubaDocument::vectorFromList(const pugi::xml_node& n, const char* attr) const {
  pugi::xml_attribute a = n.attribute(attr);
  if (!a) fail(n, "<" + std::string(n.name()) + "> needs a '" + attr + "' attribute");
  std::vector<std::string> parts = splitList(a.value());
  if (parts.size() != 3) fail(n, std::string(attr) + ": '" + a.value() + "' needs 3 numbers");
  std::string what = std::string(n.name()) + " " + attr;
  return {float(number(n, parts[0], what)), float(number(n, parts[1], what)),
          float(number(n, parts[2], what))};
}

Vec3f MitsubaDocument::xyzOf(const pugi::xml_node& n, float def) const {
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

void MitsubaDocument::checkAttributes(const pugi::xml_node& n,
                                      std::initializer_list<const char*> allowed) const {
  for (pugi::xml_attribute a : n.attributes()) {
    bool ok = false;
    for (const char* s : allowed) ok = ok || std::string_view(a.name()) == s;
    if (!ok) fail(n, "unexpected attribute '" + std::string(a.name()) + "' on <" + n.name() + ">");
  }
}

Matrix4 MitsubaDocument::transformOf(const pugi::xml_node& node) const {
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
        fail(op, "<matrix> needs 16 numbers (row-major 4x4), got " + std::to_string(parts.size()));
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

}  // namespace farm
