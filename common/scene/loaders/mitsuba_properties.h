#pragma once
// The named parameters of one Mitsuba object element (<float name="..."> and its kin), read by
// name and type, with a record of which were read so that the rest can be refused: a parameter
// nobody reads would otherwise change nothing, silently. mitsuba_document.h holds the readers of
// single values these build on.
#include <pugixml.hpp>
#include <string>
#include <utility>
#include <vector>

#include "common/math/vec.h"
#include "common/scene/loaders/mitsuba_document.h"

namespace farm {

class MitsubaProperties {
 public:
  // Splits the element's children into named parameters and nested elements (objects, refs),
  // which go to *nested; without `nested`, a nested element is an error. A parameter without a
  // name, or given twice, is an error.
  MitsubaProperties(const MitsubaDocument& document, const pugi::xml_node& node,
                    std::vector<pugi::xml_node>* nested);

  // The parameter called `name`, marked read; a null node when absent.
  pugi::xml_node take(const char* name);
  bool has(const char* name) const;
  // An error at the first parameter nobody took, naming `what` ("bsdf 'diffuse'").
  void rejectUnused(const std::string& what) const;

  // Typed reads, each `def` when absent and an error naming the parameter when of another type
  // or value.
  bool getBoolean(const char* name, bool def);
  std::string getString(const char* name, const std::string& def, pugi::xml_node* where = nullptr);
  double getNumber(const char* name, double def);  // <float> or <integer>
  // A color that must be finite and non-negative (reflectances, radiance, conductor indices).
  Spectrum getSpectrum(const char* name, const Spectrum& def);
  Vec3f getPoint(const char* name, const Vec3f& def);  // <point> or <vector>
  // An index of refraction: a positive number or a name of Mitsuba's table ("water", "bk7").
  double getIor(const char* name, double def);

 private:
  const MitsubaDocument& document_;
  std::vector<std::pair<std::string, pugi::xml_node>> entries_;
  std::vector<bool> used_;
};

}  // namespace farm
