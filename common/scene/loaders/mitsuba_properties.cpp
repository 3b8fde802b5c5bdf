#include "common/scene/loaders/mitsuba_properties.h"

#include <map>
#include <string_view>

namespace farm {

namespace {

bool isPropertyTag(std::string_view tag) {
  static const char* const kTags[] = {"float",    "integer",   "boolean",  "string",
                                      "point",    "vector",    "rgb",      "srgb",
                                      "spectrum", "blackbody", "transform"};
  for (const char* t : kTags)
    if (tag == t) return true;
  return false;
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

}  // namespace

MitsubaProperties::MitsubaProperties(const MitsubaDocument& document, const pugi::xml_node& node,
                                     std::vector<pugi::xml_node>* nested)
    : document_(document) {
  for (pugi::xml_node child : node.children()) {
    if (child.type() != pugi::node_element) continue;
    if (isPropertyTag(child.name())) {
      pugi::xml_attribute name = child.attribute("name");
      if (!name || !*name.value())
        document_.fail(child, "<" + std::string(child.name()) + "> without a name attribute");
      if (has(name.value()))
        document_.fail(child, "parameter '" + std::string(name.value()) + "' given twice");
      entries_.emplace_back(name.value(), child);
      used_.push_back(false);
    } else if (nested) {
      nested->push_back(child);
    } else {
      document_.failUnknownElement(child);
    }
  }
}

pugi::xml_node MitsubaProperties::take(const char* name) {
  for (size_t i = 0; i < entries_.size(); ++i)
    if (entries_[i].first == name) {
      used_[i] = true;
      return entries_[i].second;
    }
  return {};
}

bool MitsubaProperties::has(const char* name) const {
  for (const auto& e : entries_)
    if (e.first == name) return true;
  return false;
}

void MitsubaProperties::rejectUnused(const std::string& what) const {
  for (size_t i = 0; i < entries_.size(); ++i)
    if (!used_[i])
      document_.fail(entries_[i].second,
                     "unsupported parameter '" + entries_[i].first + "' for " + what);
}

bool MitsubaProperties::getBoolean(const char* name, bool def) {
  pugi::xml_node n = take(name);
  if (!n) return def;
  document_.requireTag(n, {"boolean"});
  std::string v = toLower(std::string(trim(document_.requireValue(n))));
  if (v == "true") return true;
  if (v == "false") return false;
  document_.fail(n, std::string("parameter '") + name + "': '" + document_.requireValue(n) +
                        "' is not a boolean (true or false)");
}

std::string MitsubaProperties::getString(const char* name, const std::string& def,
                                         pugi::xml_node* where) {
  pugi::xml_node n = take(name);
  if (where) *where = n;
  if (!n) return def;
  document_.requireTag(n, {"string"});
  return document_.requireValue(n);
}

double MitsubaProperties::getNumber(const char* name, double def) {
  pugi::xml_node n = take(name);
  if (!n) return def;
  document_.requireTag(n, {"float", "integer"});
  return document_.number(n, document_.requireValue(n), std::string("parameter '") + name + "'");
}

Spectrum MitsubaProperties::getSpectrum(const char* name, const Spectrum& def) {
  pugi::xml_node n = take(name);
  if (!n) return def;
  Spectrum s = document_.spectrumOf(n);
  if (s.x < 0 || s.y < 0 || s.z < 0)
    document_.fail(n, std::string("parameter '") + name + "' must not be negative");
  return s;
}

Vec3f MitsubaProperties::getPoint(const char* name, const Vec3f& def) {
  pugi::xml_node n = take(name);
  if (!n) return def;
  document_.requireTag(n, {"point", "vector"});
  document_.checkAttributes(n, {"name", "x", "y", "z", "value"});
  return document_.xyzOf(n, 0.0f);
}

double MitsubaProperties::getIor(const char* name, double def) {
  pugi::xml_node n = take(name);
  if (!n) return def;
  document_.requireTag(n, {"float", "integer", "string"});
  double v;
  if (std::string_view(n.name()) == "string") {
    std::string key = toLower(std::string(trim(document_.requireValue(n))));
    auto it = namedIors().find(key);
    if (it == namedIors().end())
      document_.fail(n, std::string("parameter '") + name + "': unknown material '" +
                            document_.requireValue(n) +
                            "' (give a number or a name of Mitsuba's IOR table)");
    v = it->second;
  } else {
    v = document_.number(n, document_.requireValue(n), std::string("parameter '") + name + "'");
  }
  if (!(v > 0)) document_.fail(n, std::string("parameter '") + name + "' must be > 0");
  return v;
}

}  // namespace farm
