#include "common/scene/loaders/pbrt_loader.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "common/scene/loaders/image_reader.h"
#include "common/scene/loaders/pbrt_tokenizer.h"
#include "common/scene/loaders/ply_reader.h"
#include "common/scene/loaders/vdb_reader.h"
#include "common/scene/medium.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr int kMaxIncludeDepth = 16;
constexpr int kDiskSegments = 1024;  // area deficit (2 pi / n)^2 / 6 = 6e-6 of the disk's

// Complex indices of refraction of pbrt-v4's named metal spectra ("metal-Au-eta"), as RGB:
// the spectral data integrated to linear sRGB (the table Tungsten ships; CuZn, absent there,
// is the brass of Mitsuba's documentation).
struct NamedMetal {
  const char* name;
  Spectrum eta, k;
};
const NamedMetal kNamedMetals[] = {
    {"Ag",
     {0.1552646489f, 0.1167232965f, 0.1383806959f},
     {4.8283433224f, 3.1222459278f, 2.1469504455f}},
    {"Al",
     {1.6574599595f, 0.8803689579f, 0.5212287346f},
     {9.2238691996f, 6.2695232477f, 4.8370012281f}},
    {"Au",
     {0.1431189557f, 0.3749570432f, 1.4424785571f},
     {3.9831604247f, 2.3857207478f, 1.6032152899f}},
    {"Cu",
     {0.2004376970f, 0.9240334304f, 1.1022119527f},
     {3.9129485033f, 2.4528477015f, 2.1421879552f}},
    {"CuZn", {0.444f, 0.527f, 1.094f}, {3.695f, 2.765f, 1.829f}},
    {"MgO", {2.0895885542f, 1.6507224525f, 1.5948759692f}, {0.0f, 0.0f, 0.0f}},
    {"TiO2", {3.4566203131f, 2.8017076558f, 2.9051485020f}, {0.0001026662f, 0.0f, 0.0006356902f}},
};

std::string formatNumber(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// pbrt-v3's TrowbridgeReitzDistribution::RoughnessToAlpha: a fit in log roughness.
double roughnessToAlphaV3(double roughness) {
  double x = std::log(std::max(roughness, 1e-3));
  return 1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x +
         0.000640711 * x * x * x * x;
}

// One "type name" value parameter of a directive.
struct Param {
  std::string type, name;
  std::vector<double> numbers;
  std::vector<std::string> strings;  // strings, and bools as "true" / "false"
  int line = 0;
  bool used = false;
};

struct ParamList {
  std::vector<Param> params;
  Param* find(const std::string& name) {
    for (Param& p : params)
      if (p.name == name) {
        p.used = true;
        return &p;
      }
    return nullptr;
  }
  bool has(const std::string& name) const {
    for (const Param& p : params)
      if (p.name == name) return true;
    return false;
  }
};

// A directive's words and values, with where it stands.
struct Directive {
  std::string name;
  std::vector<std::string> strings;  // positional strings
  std::vector<double> numbers;       // positional numbers
  ParamList params;
  std::string file;  // for messages: the file as the scene names it
  int line = 0;
};

struct AreaLight {
  Spectrum radiance{0.0f};
  bool active = false;
  bool twoSided = false;
};

// Material "" (pbrt-v3's no material, "none") and "interface" (pbrt-v4): a surface that only
// bounds media.
constexpr int kInterfaceMaterial = -2;

struct Attributes {
  Matrix4 ctm = Matrix4::identity();
  bool reverseOrientation = false;
  // bsdf index; -1: pbrt's default (diffuse 0.5), made on first use; kInterfaceMaterial
  int material = -1;
  AreaLight areaLight;
  // MediumInterface's named media ("" for vacuum), resolved where a shape or the camera uses
  // them, as pbrt does.
  std::string insideMedium, outsideMedium;
};

// A texture as its definition made it: built there (as pbrt does, so that it can name only
// textures defined before it), or why it could not be, told when a material uses it.
struct NamedTexture {
  int index = -1;  // in SceneDescription::textures
  std::string errorFile, error;
  int errorLine = 0;
};

constexpr int kMaxTextureDepth = 16;     // nesting of checkerboard and scale textures
constexpr size_t kMaxTextures = 100000;  // entries in SceneDescription::textures
constexpr int kMaxIncludedFiles = 1000;  // Include and Import directives in all
constexpr size_t kMaxGeometryElements = size_t(1) << 28;  // vertices + triangle corners

class PbrtLoader {
 public:
  explicit PbrtLoader(const std::string& path) : path_(path) {}

  SceneDescription load() {
    const std::string text = readSceneText(path_);
    dir_ = fs::path(path_).parent_path();
    scene_.sourcePath = path_;
    // pbrt's defaults: a 1280 x 720 film, v3's box filter, the path integrator's 5 bounces.
    scene_.camera.width = 1280;
    scene_.camera.height = 720;
    scene_.camera.filter = FilterType::Box;
    scene_.maxDepth = 6;
    includeStack_.push_back(fs::absolute(path_).lexically_normal().string());
    parseFile(text, path_, 0);
    // pbrt-v4's default filter is a gaussian of radius 1.5 and sigma 0.5; v3's a box.
    if (sawV4_ && (!sawFilter_ || gaussianDefaults_)) setGaussian(1.5, 2);
    // pbrt-v4's spots fall off by a smoothstep, v3's by the fourth power.
    if (sawV4_) {
      for (PointLightDescription& l : scene_.pointLights)
        if (l.spot) l.falloff = PointLightDescription::Falloff::PbrtV4Smoothstep;
    }
    if (!sawWorld_) throw SceneLoadError(path_, 0, "no WorldBegin: the file describes no scene");
    if (!attributeStack_.empty())
      throw SceneLoadError(path_, 0, "AttributeBegin without AttributeEnd at the end of the file");
    if (inObject_) throw SceneLoadError(path_, 0, "ObjectBegin without ObjectEnd");
    if (!sawCamera_) throw SceneLoadError(path_, 0, "no Camera directive");
    if (!cameraMedium_.empty()) {
      auto it = namedMedia_.find(cameraMedium_);
      if (it == namedMedia_.end())
        throw SceneLoadError(cameraDirectiveFile_, cameraDirectiveLine_,
                             "the camera's medium '" + cameraMedium_ + "' is not defined");
      scene_.camera.medium = it->second;
    }
    if (scene_.shapes.empty()) throw SceneLoadError(path_, 0, "the scene has no shapes");
    return std::move(scene_);
  }

 private:
  // ---- Reading directives ----

  void parseFile(const std::string& text, const std::string& file, int depth) {
    const std::vector<PbrtToken> tokens = tokenizePbrt(text, file);
    size_t i = 0;
    while (i < tokens.size()) {
      const PbrtToken& t = tokens[i];
      if (t.kind != PbrtToken::Kind::Word)
        throw SceneLoadError(file, t.line, "expected a directive, found '" + t.text + "'");
      Directive d;
      d.name = t.text;
      d.file = file;
      d.line = t.line;
      ++i;
      readArguments(tokens, &i, &d);
      if (d.name == "Include" || d.name == "Import") {
        if (d.name == "Import") sawV4_ = true;
        if (d.strings.size() != 1) fail(d, d.name + " takes one file name");
        if (depth + 1 > kMaxIncludeDepth)
          fail(d, d.name + " nested deeper than " + std::to_string(kMaxIncludeDepth) + " files");
        if (++includedFiles_ > kMaxIncludedFiles)
          fail(d, "more than " + std::to_string(kMaxIncludedFiles) + " included files");
        fs::path included = sceneFilePath(dir_, d.strings[0], "included file", d.file, d.line);
        const std::string key = fs::absolute(included).lexically_normal().string();
        if (std::find(includeStack_.begin(), includeStack_.end(), key) != includeStack_.end())
          fail(d, d.name + " of '" + d.strings[0] + "' includes itself (an include cycle)");
        includeStack_.push_back(key);
        parseFile(readSceneFile(included, "'" + d.strings[0] + "'", d.file, d.line),
                  (dir_ / d.strings[0]).string(), depth + 1);
        includeStack_.pop_back();
        continue;
      }
      apply(d);
    }
  }

  // How many positional words each directive takes before its parameter list (strings) or
  // how many numbers; -1 for directives that are unknown here.
  static int positionalStrings(const std::string& name) {
    static const std::map<std::string, int> counts = {{"Shape", 1},
                                                      {"Material", 1},
                                                      {"MakeNamedMaterial", 1},
                                                      {"NamedMaterial", 1},
                                                      {"Texture", 3},
                                                      {"LightSource", 1},
                                                      {"AreaLightSource", 1},
                                                      {"Camera", 1},
                                                      {"Film", 1},
                                                      {"PixelFilter", 1},
                                                      {"Sampler", 1},
                                                      {"Integrator", 1},
                                                      {"Accelerator", 1},
                                                      {"Include", 1},
                                                      {"Import", 1},
                                                      {"CoordinateSystem", 1},
                                                      {"CoordSysTransform", 1},
                                                      {"MakeNamedMedium", 1},
                                                      {"ObjectBegin", 1},
                                                      {"ObjectInstance", 1},
                                                      {"ColorSpace", 1},
                                                      {"Attribute", 1},
                                                      {"Option", 0},
                                                      {"MediumInterface", -2},
                                                      {"ActiveTransform", -3}};
    auto it = counts.find(name);
    return it == counts.end() ? 0 : it->second;
  }

  void readArguments(const std::vector<PbrtToken>& tokens, size_t* i, Directive* d) {
    const std::string& name = d->name;
    auto atEnd = [&] { return *i >= tokens.size(); };
    int strings = positionalStrings(name);
    if (strings == -2) {  // MediumInterface: one or two strings
      while (!atEnd() && tokens[*i].kind == PbrtToken::Kind::String && d->strings.size() < 2)
        d->strings.push_back(tokens[(*i)++].text);
      return;
    }
    if (strings == -3) {  // ActiveTransform StartTime | EndTime | All
      if (atEnd() || tokens[*i].kind != PbrtToken::Kind::Word)
        fail(*d, "ActiveTransform takes StartTime, EndTime or All");
      d->strings.push_back(tokens[(*i)++].text);
      return;
    }
    for (int k = 0; k < strings; ++k) {
      if (atEnd() || tokens[*i].kind != PbrtToken::Kind::String)
        fail(*d, name + " expects " + std::to_string(strings) + " quoted string" +
                     (strings > 1 ? "s" : "") + " first");
      d->strings.push_back(tokens[(*i)++].text);
    }
    // Bare or bracketed numbers (Translate 1 2 3, Transform [ ... ]).
    if (!atEnd() && tokens[*i].kind == PbrtToken::Kind::OpenBracket && strings == 0 &&
        name != "Option") {
      ++*i;
      while (!atEnd() && tokens[*i].kind == PbrtToken::Kind::Number)
        d->numbers.push_back(tokens[(*i)++].number);
      if (atEnd() || tokens[*i].kind != PbrtToken::Kind::CloseBracket)
        fail(*d, "expected ']' closing the numbers of " + name);
      ++*i;
    }
    while (!atEnd() && tokens[*i].kind == PbrtToken::Kind::Number)
      d->numbers.push_back(tokens[(*i)++].number);
    // The parameter list: "type name" value pairs.
    std::set<std::string> names;
    while (!atEnd() && tokens[*i].kind == PbrtToken::Kind::String) {
      const PbrtToken& decl = tokens[(*i)++];
      Param p;
      p.line = decl.line;
      std::string text = decl.text;
      size_t a = text.find_first_not_of(" \t");
      size_t sp = text.find_first_of(" \t", a);
      size_t b = sp == std::string::npos ? sp : text.find_first_not_of(" \t", sp);
      if (a == std::string::npos || sp == std::string::npos || b == std::string::npos)
        throw SceneLoadError(d->file, decl.line,
                             "'" + text + "' is not a parameter declaration (\"type name\")");
      p.type = text.substr(a, sp - a);
      size_t e = text.find_last_not_of(" \t");
      p.name = text.substr(b, e - b + 1);
      if (p.name.find_first_of(" \t") != std::string::npos)
        throw SceneLoadError(d->file, decl.line,
                             "'" + text + "' is not a parameter declaration (\"type name\")");
      if (p.type == "point") p.type = "point3";
      if (p.type == "normal") p.type = "normal3";
      if (p.type == "vector") p.type = "vector3";
      if (p.type == "color") p.type = "rgb";
      auto readValue = [&](const PbrtToken& v) {
        if (v.kind == PbrtToken::Kind::Number) {
          p.numbers.push_back(v.number);
        } else if (v.kind == PbrtToken::Kind::String ||
                   (v.kind == PbrtToken::Kind::Word && (v.text == "true" || v.text == "false"))) {
          p.strings.push_back(v.text);
        } else {
          throw SceneLoadError(d->file, v.line,
                               "unexpected '" + v.text + "' in the value of '" + p.name + "'");
        }
      };
      if (atEnd())
        throw SceneLoadError(d->file, decl.line, "parameter '" + p.name + "' has no value");
      if (tokens[*i].kind == PbrtToken::Kind::OpenBracket) {
        ++*i;
        while (!atEnd() && tokens[*i].kind != PbrtToken::Kind::CloseBracket)
          readValue(tokens[(*i)++]);
        if (atEnd())
          throw SceneLoadError(d->file, decl.line, "expected ']' closing '" + p.name + "'");
        ++*i;
      } else {
        readValue(tokens[(*i)++]);
      }
      if (!p.numbers.empty() && !p.strings.empty())
        throw SceneLoadError(d->file, p.line,
                             "parameter '" + p.name + "' mixes numbers and strings");
      if (!names.insert(p.name).second)
        throw SceneLoadError(d->file, p.line, "parameter '" + p.name + "' given twice");
      d->params.params.push_back(std::move(p));
    }
  }

  // ---- Errors ----

  [[noreturn]] void fail(const Directive& d, const std::string& problem) const {
    throw SceneLoadError(d.file, d.line, problem);
  }
  [[noreturn]] void failParam(const Directive& d, const Param& p,
                              const std::string& problem) const {
    throw SceneLoadError(d.file, p.line ? p.line : d.line, problem);
  }
  // Every parameter not read is an error: unknown ones would otherwise change nothing silently.
  void rejectUnused(const Directive& d, const std::string& what) const {
    for (const Param& p : d.params.params)
      if (!p.used)
        failParam(d, p, what + ": parameter '" + p.type + " " + p.name + "' is not supported");
  }

  void warn(const Directive& d, const std::string& what) {
    scene_.warnings.push_back(formatLoadMessage(d.file, d.line, what));
  }

  // ---- Typed parameter access ----

  Param* typed(Directive& d, const std::string& name, std::initializer_list<const char*> types) {
    Param* p = d.params.find(name);
    if (!p) return nullptr;
    for (const char* t : types)
      if (p->type == t) return p;
    std::string allowed;
    for (const char* t : types) allowed += (allowed.empty() ? "" : " or ") + std::string(t);
    failParam(d, *p, "parameter '" + name + "' must be of type " + allowed + ", not " + p->type);
  }
  double getFloat(Directive& d, const std::string& name, double def) {
    Param* p = typed(d, name, {"float", "integer"});
    if (!p) return def;
    if (p->numbers.size() != 1) failParam(d, *p, "parameter '" + name + "' takes one number");
    return p->numbers[0];
  }
  long long getInt(Directive& d, const std::string& name, long long def) {
    Param* p = typed(d, name, {"integer"});
    if (!p) return def;
    if (p->numbers.size() != 1) failParam(d, *p, "parameter '" + name + "' takes one integer");
    double v = p->numbers[0];
    if (v != std::floor(v) || std::fabs(v) > 1e15)
      failParam(d, *p, "parameter '" + name + "' is not an integer");
    return (long long)v;
  }
  bool getBool(Directive& d, const std::string& name, bool def) {
    Param* p = typed(d, name, {"bool"});
    if (!p) return def;
    if (p->strings.size() != 1 || (p->strings[0] != "true" && p->strings[0] != "false"))
      failParam(d, *p, "parameter '" + name + "' must be true or false");
    return p->strings[0] == "true";
  }
  std::string getString(Directive& d, const std::string& name, const std::string& def) {
    Param* p = typed(d, name, {"string"});
    if (!p) return def;
    if (p->strings.size() != 1) failParam(d, *p, "parameter '" + name + "' takes one string");
    return p->strings[0];
  }
  std::vector<double> getNumbers(Directive& d, const std::string& name,
                                 std::initializer_list<const char*> types, size_t multiple) {
    Param* p = typed(d, name, types);
    if (!p) return {};
    if (!p->strings.empty() || p->numbers.size() % multiple != 0)
      failParam(
          d, *p,
          "parameter '" + name + "' needs a multiple of " + std::to_string(multiple) + " numbers");
    return p->numbers;
  }

  // An RGB (or named metal) spectrum; `isTexture` tells whether a "texture" reference is
  // allowed here (then *texture receives its index and the spectrum is unused).
  bool getSpectrum(Directive& d, const std::string& name, Spectrum* out, int* texture = nullptr) {
    Param* p = d.params.find(name);
    if (!p) return false;
    if (p->type == "texture") {
      if (!texture) failParam(d, *p, "parameter '" + name + "' cannot be a texture here");
      if (p->strings.size() != 1) failParam(d, *p, "parameter '" + name + "' names one texture");
      *texture = useTexture(d, *p, p->strings[0], false);
      return true;
    }
    if (p->type == "rgb") {
      if (p->numbers.size() != 3) failParam(d, *p, "rgb parameter '" + name + "' takes 3 numbers");
      for (double v : p->numbers)
        if (v < 0) failParam(d, *p, "rgb parameter '" + name + "' is negative");
      *out = Spectrum(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2]));
      return true;
    }
    if (p->type == "float") {
      if (p->numbers.size() != 1) failParam(d, *p, "parameter '" + name + "' takes one number");
      if (p->numbers[0] < 0) failParam(d, *p, "parameter '" + name + "' is negative");
      *out = Spectrum(float(p->numbers[0]));
      return true;
    }
    if (p->type == "spectrum") {
      if (p->strings.size() == 1) {
        const std::string& s = p->strings[0];
        for (const NamedMetal& m : kNamedMetals) {
          const std::string prefix = std::string("metal-") + m.name + "-";
          if (s == prefix + "eta") return *out = m.eta, true;
          if (s == prefix + "k") return *out = m.k, true;
        }
        failParam(d, *p,
                  "spectrum '" + s +
                      "' is not supported (named spectra: metal-{Ag,Al,Au,Cu,CuZn,MgO,"
                      "TiO2}-{eta,k}); give it as rgb");
      }
      failParam(d, *p, "sampled spectrum '" + name + "' is not supported: give it as rgb");
    }
    if (p->type == "blackbody")
      failParam(d, *p, "blackbody spectrum '" + name + "' is not supported: give it as rgb");
    failParam(d, *p, "parameter '" + name + "' must be an rgb spectrum, not " + p->type);
  }

  // ---- Directives ----

  void apply(Directive& d) {
    const std::string& n = d.name;
    if (n == "Translate" || n == "Scale" || n == "Rotate" || n == "LookAt" || n == "Transform" ||
        n == "ConcatTransform" || n == "Identity" || n == "CoordinateSystem" ||
        n == "CoordSysTransform" || n == "ReverseOrientation" || n == "TransformBegin" ||
        n == "TransformEnd" || n == "AttributeBegin" || n == "AttributeEnd" ||
        n == "ActiveTransform" || n == "TransformTimes") {
      applyTransformDirective(d);
    } else if (n == "Camera") {
      beforeWorld(d);
      parseCamera(d);
    } else if (n == "Film") {
      beforeWorld(d);
      parseFilm(d);
    } else if (n == "PixelFilter") {
      beforeWorld(d);
      parseFilter(d);
    } else if (n == "Integrator") {
      beforeWorld(d);
      parseIntegrator(d);
    } else if (n == "Sampler") {
      beforeWorld(d);
      warn(d, "Sampler '" + d.strings[0] + "' ignored: the farm's settings choose the samples");
    } else if (n == "Accelerator") {
      beforeWorld(d);  // an acceleration structure does not change the picture
    } else if (n == "ColorSpace") {
      if (d.strings[0] != "srgb")
        fail(d, "color space '" + d.strings[0] + "' is not supported (srgb only)");
    } else if (n == "Option") {
      fail(d, "Option is not supported");
    } else if (n == "WorldBegin") {
      if (sawWorld_) fail(d, "a second WorldBegin");
      sawWorld_ = true;
      attrs_.ctm = Matrix4::identity();
      namedCoordinateSystems_["world"] = attrs_.ctm;
    } else if (n == "WorldEnd") {
      inWorld(d);
    } else if (n == "Texture") {
      inWorld(d);
      defineTexture(d);
    } else if (n == "Material") {
      inWorld(d);
      attrs_.material = makeMaterial(d, d.strings[0]);
    } else if (n == "MakeNamedMaterial") {
      inWorld(d);
      std::string type = getString(d, "type", "");
      if (type.empty()) fail(d, "MakeNamedMaterial '" + d.strings[0] + "' has no \"string type\"");
      namedMaterials_[d.strings[0]] = makeMaterial(d, type);
    } else if (n == "NamedMaterial") {
      inWorld(d);
      auto it = namedMaterials_.find(d.strings[0]);
      if (it == namedMaterials_.end())
        fail(d, "named material '" + d.strings[0] + "' is not defined");
      attrs_.material = it->second;
    } else if (n == "AreaLightSource") {
      inWorld(d);
      parseAreaLight(d);
    } else if (n == "Shape") {
      inWorld(d);
      parseShape(d);
    } else if (n == "LightSource") {
      inWorld(d);
      parseLightSource(d);
    } else if (n == "MakeNamedMedium") {
      if (namedMedia_.count(d.strings[0]))
        fail(d, "medium '" + d.strings[0] + "' is defined twice");
      namedMedia_[d.strings[0]] = makeMedium(d);
    } else if (n == "MediumInterface") {
      // One name: the same medium on both sides; two: inside, then outside.
      if (d.strings.empty()) fail(d, "MediumInterface names one or two media");
      attrs_.insideMedium = d.strings[0];
      attrs_.outsideMedium = d.strings.size() > 1 ? d.strings[1] : d.strings[0];
    } else if (n == "ObjectBegin") {
      inWorld(d);
      if (inObject_) fail(d, "ObjectBegin inside the definition of object '" + objectName_ + "'");
      if (objects_.count(d.strings[0])) fail(d, "object '" + d.strings[0] + "' is defined twice");
      // As pbrt: an attribute block around the definition.
      attributeStack_.push_back(attrs_);
      objectBlockDepth_ = attributeStack_.size();
      inObject_ = true;
      objectName_ = d.strings[0];
      objects_[objectName_];
    } else if (n == "ObjectEnd") {
      if (!inObject_) fail(d, "ObjectEnd without ObjectBegin");
      if (attributeStack_.size() != objectBlockDepth_)
        fail(d, "ObjectEnd inside an AttributeBegin that the object's definition opened");
      inObject_ = false;
      attrs_ = attributeStack_.back();
      attributeStack_.pop_back();
    } else if (n == "ObjectInstance") {
      inWorld(d);
      instantiate(d);
    } else if (n == "Attribute") {
      fail(d, "Attribute (default parameters) is not supported");
    } else {
      fail(d, "unknown directive '" + n + "'");
    }
  }

  void beforeWorld(const Directive& d) const {
    if (sawWorld_) fail(d, d.name + " must come before WorldBegin");
  }
  void inWorld(const Directive& d) const {
    if (!sawWorld_) fail(d, d.name + " must come after WorldBegin");
  }

  void needNumbers(const Directive& d, size_t count) const {
    if (d.numbers.size() != count)
      fail(d, d.name + " takes " + std::to_string(count) + " numbers, not " +
                  std::to_string(d.numbers.size()));
  }

  static Vec3f vec(const std::vector<double>& v, size_t at) {
    return Vec3f(float(v[at]), float(v[at + 1]), float(v[at + 2]));
  }

  // pbrt writes matrices column by column (its Transform takes the transpose of the row-major
  // array it is given).
  static Matrix4 matrixOf(const std::vector<double>& v) {
    Matrix4 m;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) m.m[r][c] = v[size_t(4 * c + r)];
    return m;
  }

  void applyTransformDirective(Directive& d) {
    const std::string& n = d.name;
    Matrix4& ctm = attrs_.ctm;
    if (n == "Translate") {
      needNumbers(d, 3);
      ctm = ctm * Matrix4::translate(vec(d.numbers, 0));
    } else if (n == "Scale") {
      needNumbers(d, 3);
      ctm = ctm * Matrix4::scale(vec(d.numbers, 0));
    } else if (n == "Rotate") {
      needNumbers(d, 4);
      Vec3f axis = vec(d.numbers, 1);
      if (!(length(axis) > 0)) fail(d, "Rotate about a zero axis");
      ctm = ctm * Matrix4::rotate(axis, d.numbers[0]);
    } else if (n == "LookAt") {
      needNumbers(d, 9);
      // pbrt's LookAt is the inverse of the camera-to-world matrix Matrix4::lookAt builds: both
      // take right = up x dir.
      Matrix4 cameraToWorld =
          Matrix4::lookAt(vec(d.numbers, 0), vec(d.numbers, 3), vec(d.numbers, 6));
      if (!cameraToWorld.isFinite())
        fail(d, "LookAt with the up vector along the view direction (or eye at the target)");
      ctm = ctm * cameraToWorld.inverse();
    } else if (n == "Transform" || n == "ConcatTransform") {
      needNumbers(d, 16);
      Matrix4 m = matrixOf(d.numbers);
      ctm = n == "Transform" ? m : ctm * m;
    } else if (n == "Identity") {
      ctm = Matrix4::identity();
    } else if (n == "CoordinateSystem") {
      namedCoordinateSystems_[d.strings[0]] = ctm;
    } else if (n == "CoordSysTransform") {
      auto it = namedCoordinateSystems_.find(d.strings[0]);
      if (it == namedCoordinateSystems_.end())
        fail(d, "coordinate system '" + d.strings[0] + "' is not defined");
      ctm = it->second;
    } else if (n == "ReverseOrientation") {
      attrs_.reverseOrientation = !attrs_.reverseOrientation;
    } else if (n == "TransformBegin") {
      transformStack_.push_back(ctm);
    } else if (n == "TransformEnd") {
      if (transformStack_.empty()) fail(d, "TransformEnd without TransformBegin");
      ctm = transformStack_.back();
      transformStack_.pop_back();
    } else if (n == "AttributeBegin") {
      attributeStack_.push_back(attrs_);
    } else if (n == "AttributeEnd") {
      if (attributeStack_.empty()) fail(d, "AttributeEnd without AttributeBegin");
      if (inObject_ && attributeStack_.size() <= objectBlockDepth_)
        fail(d, "AttributeEnd would end the definition of object '" + objectName_ +
                    "' (it needs ObjectEnd)");
      attrs_ = attributeStack_.back();
      attributeStack_.pop_back();
    } else if (n == "ActiveTransform") {
      if (d.strings[0] != "All")
        fail(d, "ActiveTransform " + d.strings[0] + ": motion blur is not supported");
    } else {  // TransformTimes
      fail(d, "TransformTimes: motion blur is not supported");
    }
    if (!ctm.isFinite()) fail(d, "the transformation is not finite (a zero scale?)");
  }

  // ---- Camera, film, filter, integrator ----

  void parseCamera(Directive& d) {
    if (sawCamera_) fail(d, "a second Camera");
    sawCamera_ = true;
    // pbrt: the camera sits in the current outside medium.
    cameraMedium_ = attrs_.outsideMedium;
    cameraDirectiveFile_ = d.file;
    cameraDirectiveLine_ = d.line;
    if (d.strings[0] != "perspective")
      fail(d, "camera '" + d.strings[0] + "' is not supported (perspective only)");
    double fov = getFloat(d, "fov", 90);
    if (!(fov > 0 && fov < 180)) fail(d, "fov must be in (0, 180) degrees");
    double lensRadius = getFloat(d, "lensradius", 0);
    double focusDistance = getFloat(d, "focaldistance", 1e6);
    if (!(lensRadius >= 0)) fail(d, "lensradius must be >= 0");
    if (!(focusDistance > 0)) fail(d, "focaldistance must be > 0");
    getFloat(d, "shutteropen", 0);
    getFloat(d, "shutterclose", 1);
    rejectUnused(d, "Camera");
    // The CTM is world-to-camera. pbrt's camera space has +x to the image's right; ours (as
    // Mitsuba's) to the left, hence the mirror.
    const Matrix4 cameraToWorld = attrs_.ctm.inverse();
    if (!cameraToWorld.isFinite()) fail(d, "the camera transformation is singular");
    namedCoordinateSystems_["camera"] = cameraToWorld;
    scene_.camera.toWorld = cameraToWorld * Matrix4::scale(Vec3f(-1, 1, 1));
    // Our camera takes the axes' directions; a shear would be lost, so refuse it.
    Vec3f axes[3];
    for (int j = 0; j < 3; ++j) {
      Vec3f e(j == 0, j == 1, j == 2);
      axes[j] = normalize(cameraToWorld.applyVector(e));
    }
    for (int j = 0; j < 3; ++j)
      if (std::fabs(dot(axes[j], axes[(j + 1) % 3])) > 1e-4f)
        fail(d, "the camera transformation has a shear");
    // pbrt scales its rays' directions by it: a non-uniform scale would stretch the view.
    float lengths[3];
    for (int j = 0; j < 3; ++j)
      lengths[j] = length(cameraToWorld.applyVector(Vec3f(j == 0, j == 1, j == 2)));
    if (std::fabs(lengths[0] - lengths[1]) > 1e-4f * lengths[2] ||
        std::fabs(lengths[1] - lengths[2]) > 1e-4f * lengths[2])
      fail(d, "the camera transformation has a non-uniform scale");
    scene_.camera.fovDegrees = float(fov);
    // Lens radius and focus distance are in camera space: to world units by the (uniform)
    // scale of the camera's transformation.
    const double scale = (double(lengths[0]) + lengths[1] + lengths[2]) / 3;
    scene_.camera.lensRadius = float(lensRadius * scale);
    scene_.camera.focusDistance = float(focusDistance * scale);
    scene_.camera.fovAxis = FovAxis::Smaller;  // pbrt's fov spans the shorter image axis
  }

  void parseFilm(Directive& d) {
    const std::string& type = d.strings[0];
    if (type != "image" && type != "rgb" && type != "gbuffer")
      fail(d, "film '" + type + "' is not supported (image, rgb)");
    long long w = getInt(d, "xresolution", 1280), h = getInt(d, "yresolution", 720);
    if (w < 1 || h < 1 || w > 65536 || h > 65536)
      fail(d, "film resolution " + std::to_string(w) + "x" + std::to_string(h) +
                  " is outside 1..65536");
    if (w * h > (1ll << 28)) fail(d, "film of more than 2^28 pixels");
    getString(d, "filename", "");  // the farm names its own output
    rejectUnused(d, "Film");
    scene_.camera.width = int(w);
    scene_.camera.height = int(h);
  }

  void parseFilter(Directive& d) {
    sawFilter_ = true;
    const std::string& type = d.strings[0];
    // v3 names the radius "xwidth", v4 "xradius".
    auto radius = [&](const char* axis, double def) {
      std::string v3 = std::string(axis) + "width", v4 = std::string(axis) + "radius";
      double r = getFloat(d, v3, def);
      return getFloat(d, v4, r);
    };
    if (type == "box") {
      double rx = radius("x", 0.5), ry = radius("y", 0.5);
      if (rx != 0.5 || ry != 0.5) fail(d, "box filter of radius other than 0.5 is not supported");
      scene_.camera.filter = FilterType::Box;
    } else if (type == "triangle") {
      double rx = radius("x", 2), ry = radius("y", 2);
      if (rx != 1 || ry != 1)
        fail(d, "triangle filter of radius " + std::to_string(rx) + " x " + std::to_string(ry) +
                    " is not supported (radius 1 only)");
      scene_.camera.filter = FilterType::Tent;
    } else if (type == "gaussian") {
      // v3: xwidth (2) and alpha (2); v4: xradius (1.5) and sigma (0.5), alpha = 1 / (2 sigma^2).
      const bool v4 = d.params.has("xradius") || d.params.has("yradius") || d.params.has("sigma");
      // Without parameters the version decides the radius (v3's 2, v4's 1.5): settled at the
      // end, when the file's materials have told it.
      gaussianDefaults_ = d.params.params.empty();
      const double rx = radius("x", v4 ? 1.5 : 2), ry = radius("y", v4 ? 1.5 : 2);
      if (rx != ry) fail(d, "a gaussian filter with different x and y radii is not supported");
      // Below half a pixel some film points would reach no pixel centre.
      if (!(rx >= 0.5 && rx <= 16)) fail(d, "gaussian filter radius must be in [0.5, 16] pixels");
      double alpha = getFloat(d, "alpha", 2);
      if (d.params.has("sigma")) {
        const double sigma = getFloat(d, "sigma", 0.5);
        if (!(sigma > 0)) fail(d, "gaussian sigma must be > 0");
        alpha = 1 / (2 * sigma * sigma);
      }
      if (!(alpha >= 0.01 && alpha <= 100)) fail(d, "gaussian alpha must be in [0.01, 100]");
      setGaussian(rx, alpha);
    } else {
      fail(d, "pixel filter '" + type +
                  "' is not supported (box of radius 0.5, triangle of radius 1, gaussian)");
    }
    rejectUnused(d, "PixelFilter");
  }

  void setGaussian(double radius, double alpha) {
    scene_.camera.filter = FilterType::Gaussian;
    scene_.camera.filterRadius = float(radius);
    scene_.camera.filterAlpha = float(alpha);
  }

  void parseIntegrator(Directive& d) {
    static const char* const kUnbiased[] = {"path",       "volpath",   "bdpt",
                                            "mlt",        "sppm",      "simplepath",
                                            "randomwalk", "lightpath", "simplevolpath"};
    const std::string& type = d.strings[0];
    bool ok = false;
    for (const char* t : kUnbiased) ok = ok || type == t;
    if (!ok)
      fail(d, "integrator '" + type +
                  "' is not supported: its picture is not the light transport the farm renders");
    long long depth = getInt(d, "maxdepth", 5);
    if (depth < 0) fail(d, "maxdepth must be >= 0");
    if (depth > 100000) fail(d, "maxdepth is absurdly large");
    // pbrt counts bounces (0: emitted light only); the farm counts edges, as Mitsuba does.
    scene_.maxDepth = int(depth) + 1;
    std::string ignored;
    for (Param& p : d.params.params)
      if (!p.used) {
        p.used = true;
        ignored += (ignored.empty() ? "" : ", ") + p.name;
      }
    if (!ignored.empty())
      warn(d,
           "integrator parameters ignored (the farm's settings choose the algorithm): " + ignored);
  }

  // ---- Textures ----

  void defineTexture(Directive& d) {
    const std::string& kind = d.strings[1];
    if (kind != "spectrum" && kind != "color" && kind != "float")
      fail(d, "texture type '" + kind + "' must be spectrum or float");
    const bool isFloat = kind == "float";
    NamedTexture t;
    // A scene may declare textures it never reads (bump maps, say): what cannot be built is an
    // error only where a material uses it.
    try {
      t.index = buildTexture(d, isFloat);
    } catch (const SceneLoadError& e) {
      t.errorFile = e.file();
      t.errorLine = e.line();
      t.error = e.problem();
    }
    (isFloat ? floatTextures_ : spectrumTextures_)[d.strings[0]] = std::move(t);
  }

  // The index of named texture `name`, for a parameter `p` of `user`.
  int useTexture(const Directive& user, const Param& p, const std::string& name, bool isFloat) {
    auto& table = isFloat ? floatTextures_ : spectrumTextures_;
    auto it = table.find(name);
    if (it == table.end()) {
      auto& other = isFloat ? spectrumTextures_ : floatTextures_;
      if (other.count(name))
        failParam(user, p,
                  std::string(isFloat ? "spectrum" : "float") + " texture '" + name +
                      "' used where a " + (isFloat ? "float" : "spectrum") + " texture is needed");
      failParam(user, p, "texture '" + name + "' is not defined");
    }
    if (it->second.index < 0)
      throw SceneLoadError(it->second.errorFile, it->second.errorLine, it->second.error);
    return it->second.index;
  }

  int addTexture(TextureDescription t) {
    int depth = 1;
    for (int child : {t.tex1, t.tex2})
      if (child >= 0) depth = std::max(depth, textureDepth_[size_t(child)] + 1);
    if (depth > kMaxTextureDepth)
      throw SceneLoadError(path_, 0,
                           "textures nested deeper than " + std::to_string(kMaxTextureDepth) +
                               " (" + t.origin + ")");
    if (scene_.textures.size() >= kMaxTextures)
      throw SceneLoadError(path_, 0, "more than " + std::to_string(kMaxTextures) + " textures");
    textureDepth_.push_back(depth);
    scene_.textures.push_back(std::move(t));
    return int(scene_.textures.size()) - 1;
  }
  int constantTexture(const Spectrum& v) {
    TextureDescription t;
    t.type = TextureDescription::Type::Constant;
    t.value = v;
    return addTexture(std::move(t));
  }

  // A texture argument: a named texture or a value (of type float, rgb or spectrum).
  int textureArgument(Directive& d, const std::string& name, bool isFloat, float def) {
    Param* p = d.params.find(name);
    if (!p) return constantTexture(Spectrum(def));
    if (p->type == "texture") {
      if (p->strings.size() != 1) failParam(d, *p, "parameter '" + name + "' names one texture");
      return useTexture(d, *p, p->strings[0], isFloat);
    }
    p->used = false;
    Spectrum v;
    getSpectrum(d, name, &v);
    return constantTexture(v);
  }

  void readMapping(Directive& d, TextureDescription* t) {
    std::string mapping = getString(d, "mapping", "uv");
    if (mapping != "uv") fail(d, "texture mapping '" + mapping + "' is not supported (uv only)");
    t->uScale = float(getFloat(d, "uscale", 1));
    t->vScale = float(getFloat(d, "vscale", 1));
    t->uOffset = float(getFloat(d, "udelta", 0));
    t->vOffset = float(getFloat(d, "vdelta", 0));
  }

  int buildTexture(Directive& d, bool isFloat) {
    const std::string& cls = d.strings[2];
    const std::string what = "texture '" + d.strings[0] + "' (" + cls + ")";
    TextureDescription t;
    t.origin =
        fs::path(d.file).filename().string() + ":" + std::to_string(d.line) + " (" + cls + ")";
    int result;
    if (cls == "imagemap") {
      if (isFloat) fail(d, "float image textures are not supported (only reflectance is textured)");
      std::string filename = getString(d, "filename", "");
      if (filename.empty()) fail(d, what + " has no filename");
      std::string wrap = getString(d, "wrap", "repeat");
      if (wrap == "repeat")
        t.wrap = TextureWrap::Repeat;
      else if (wrap == "clamp")
        t.wrap = TextureWrap::Clamp;
      else if (wrap == "black")
        t.wrap = TextureWrap::Black;
      else
        fail(d, "texture wrap '" + wrap + "' is not supported (repeat, clamp, black)");
      TextureEncoding encoding = TextureEncoding::Automatic;
      if (d.params.has("gamma"))
        encoding = getBool(d, "gamma", false) ? TextureEncoding::SRGB : TextureEncoding::Linear;
      if (d.params.has("encoding")) {
        std::string e = getString(d, "encoding", "sRGB");
        if (e == "sRGB")
          encoding = TextureEncoding::SRGB;
        else if (e == "linear")
          encoding = TextureEncoding::Linear;
        else
          fail(d, "texture encoding '" + e + "' is not supported (sRGB, linear)");
      }
      if (getBool(d, "invert", false)) fail(d, "inverted image textures are not supported");
      double scale = getFloat(d, "scale", 1);
      if (!(scale >= 0)) fail(d, "texture scale must be >= 0");
      bool trilinear = getBool(d, "trilinear", false);
      std::string filter = getString(d, "filter", "bilinear");
      getFloat(d, "maxanisotropy", 8);
      if (trilinear || (filter != "bilinear" && filter != "point"))
        warn(d, what +
                    ": filtered bilinearly (no MIP map); the pixel filter and the samples "
                    "average the texture over each pixel");
      readMapping(d, &t);
      rejectUnused(d, what);
      t.type = TextureDescription::Type::Image;
      t.image = images_.load(dir_, filename, encoding, d.file, d.line);
      t.origin = fs::path(d.file).filename().string() + ":" + std::to_string(d.line) +
                 " (imagemap " + filename + ")";
      result = addTexture(std::move(t));
      if (scale != 1) {
        TextureDescription s;
        s.type = TextureDescription::Type::Scale;
        s.tex1 = result;
        s.tex2 = constantTexture(Spectrum(float(scale)));
        result = addTexture(std::move(s));
      }
    } else if (cls == "checkerboard") {
      if (getInt(d, "dimension", 2) != 2) fail(d, "3D checkerboards are not supported");
      std::string aa = getString(d, "aamode", "closedform");
      if (aa != "none")
        warn(d, what +
                    ": not antialiased by a closed form; the pixel filter and the samples "
                    "average it over each pixel");
      t.tex1 = textureArgument(d, "tex1", isFloat, 1);
      t.tex2 = textureArgument(d, "tex2", isFloat, 0);
      readMapping(d, &t);
      rejectUnused(d, what);
      t.type = TextureDescription::Type::Checkerboard;
      result = addTexture(std::move(t));
    } else if (cls == "scale") {
      // v3: tex1 * tex2; v4: tex * scale (a float).
      if (d.params.has("tex") || d.params.has("scale")) {
        t.tex1 = textureArgument(d, "tex", isFloat, 1);
        t.tex2 = textureArgument(d, "scale", true, 1);
      } else {
        t.tex1 = textureArgument(d, "tex1", isFloat, 1);
        t.tex2 = textureArgument(d, "tex2", isFloat, 1);
      }
      rejectUnused(d, what);
      t.type = TextureDescription::Type::Scale;
      result = addTexture(std::move(t));
    } else if (cls == "constant") {
      Spectrum v(1.0f);
      getSpectrum(d, "value", &v);
      rejectUnused(d, what);
      result = constantTexture(v);
    } else {
      fail(d, "texture class '" + cls +
                  "' is not supported (imagemap, checkerboard, scale, constant)");
    }
    return result;
  }

  // ---- Materials ----

  // Roughness of a (rough) conductor or dielectric as alpha, or 0 for a smooth one. v3's
  // materials remap with a polynomial, v4's with a square root; both have remaproughness.
  double roughness(Directive& d, bool v4, double def, bool metalV3 = false) {
    for (const char* name : {"roughness", "uroughness", "vroughness"}) {
      Param* p = d.params.find(name);
      if (p && p->type == "texture") failParam(d, *p, "textured roughness is not supported");
      if (p) p->used = false;
    }
    double r = getFloat(d, "roughness", def);
    double u = getFloat(d, "uroughness", r), v = getFloat(d, "vroughness", r);
    if (u != v) fail(d, "anisotropic roughness (uroughness != vroughness) is not supported");
    if (!(u >= 0)) fail(d, "roughness must be >= 0");
    bool remap = getBool(d, "remaproughness", true);
    double alpha = remap ? (v4 ? std::sqrt(u) : roughnessToAlphaV3(u)) : u;
    // pbrt-v4 renders microfacets of alpha below 1e-3 as smooth. v3 remaps roughness 0 to
    // its clamp 1e-3 (alpha 0.047) for metal, and has a smooth path for glass only.
    if (v4 ? alpha < 1e-3 : (alpha == 0 || (u == 0 && !metalV3))) return 0;
    return alpha;
  }

  // An index of refraction given as one float (`def` without the parameter); a spectral one is
  // refused.
  double scalarIndex(Directive& d, const Param* eta, double def) {
    if (!eta) return def;
    if (eta->type != "float" || eta->numbers.size() != 1)
      failParam(d, *eta,
                "a dispersive (spectral) index of refraction is not supported: give one float");
    return eta->numbers[0];
  }

  // A diffuse reflectance, which may be a texture (`def` where the material does not give it).
  void readReflectance(Directive& d, const std::string& name, float def, BsdfDescription* b) {
    b->reflectance = Spectrum(def);
    int texture = -1;
    getSpectrum(d, name, &b->reflectance, &texture);
    b->reflectanceTexture = texture;
  }

  int makeMaterial(Directive& d, const std::string& type) {
    if (type == "" || type == "none" || type == "interface") {
      getString(d, "type", "");  // MakeNamedMaterial's, read already
      rejectUnused(d, "material '" + type + "'");
      return kInterfaceMaterial;
    }
    if (type == "diffuse" || type == "conductor" || type == "dielectric" || type == "coateddiffuse")
      sawV4_ = true;
    const std::string what = "material '" + type + "'";
    for (const char* bump : {"bumpmap", "displacement"})
      if (d.params.has(bump))
        failParam(d, *d.params.find(bump), what + ": bump and displacement maps are not supported");
    BsdfDescription b;
    if (type == "matte" || type == "diffuse") {
      b.type = BsdfDescription::Type::Diffuse;
      b.twoSided = true;  // pbrt's BSDFs scatter on both sides of a surface
      readReflectance(d, type == "matte" ? "Kd" : "reflectance", 0.5f, &b);
      if (type == "matte" && getFloat(d, "sigma", 0) != 0)
        fail(d, "Oren-Nayar matte (sigma > 0) is not supported");
    } else if (type == "metal" || type == "conductor") {
      const bool v4 = type == "conductor";
      if (v4 && d.params.has("reflectance"))
        fail(d, "conductor given by reflectance is not supported: give eta and k");
      b.eta = kNamedMetals[3].eta;  // copper, both versions' default
      b.k = kNamedMetals[3].k;
      getSpectrum(d, "eta", &b.eta);
      getSpectrum(d, "k", &b.k);
      double alpha = roughness(d, v4, v4 ? 0.0 : 0.01, !v4);
      b.twoSided = true;
      b.extEta = 1.0f;
      if (alpha > 0) {
        b.type = BsdfDescription::Type::RoughConductor;
        b.distribution = MicrofacetDistribution::GGX;  // pbrt's Trowbridge-Reitz
        b.alpha = float(alpha);
      } else {
        b.type = BsdfDescription::Type::Conductor;
      }
    } else if (type == "mirror") {
      b.type = BsdfDescription::Type::Conductor;
      b.twoSided = true;
      b.eta = Spectrum(0.0f);  // eta 0 + 1i reflects everything; Kr scales it
      b.k = Spectrum(1.0f);
      b.specularReflectance = Spectrum(0.9f);
      getSpectrum(d, "Kr", &b.specularReflectance);
    } else if (type == "glass" || type == "dielectric") {
      const bool v4 = type == "dielectric";
      Param* etaParam = d.params.find(v4 ? "eta" : "index");
      if (!v4 && !etaParam) etaParam = d.params.find("eta");
      const double eta = scalarIndex(d, etaParam, 1.5);
      if (!(eta > 0) || eta > 100) fail(d, "index of refraction must be in (0, 100]");
      if (!v4) {
        Spectrum kr(1.0f), kt(1.0f);
        getSpectrum(d, "Kr", &kr);
        getSpectrum(d, "Kt", &kt);
        auto one = [](const Spectrum& v) { return v.x == 1 && v.y == 1 && v.z == 1; };
        if (!one(kr) || !one(kt)) fail(d, "tinted glass (Kr or Kt other than 1) is not supported");
      }
      double alpha = roughness(d, v4, 0.0);
      b.intIOR = float(eta);
      b.extIOR = 1.0f;
      if (eta == 1) fail(d, "glass of index 1 does not refract; leave the surface out");
      if (alpha > 0) {
        b.type = BsdfDescription::Type::RoughDielectric;
        b.distribution = MicrofacetDistribution::GGX;
        b.alpha = float(alpha);
      } else {
        b.type = BsdfDescription::Type::Dielectric;
      }
    } else if (type == "" || type == "none" || type == "interface") {
      fail(d, "material '" + type + "' (a boundary of media only) is not supported");
    } else if (type == "plastic") {
      // pbrt-v3's plastic: Lambertian Kd plus a Trowbridge-Reitz lobe Ks with a dielectric's
      // Fresnel term. pbrt-v3 takes that term from inside the coating (index 1.5 to 1, total
      // reflection beyond 42 degrees); the farm takes the physical one, from the air.
      b.type = BsdfDescription::Type::Plastic;
      b.twoSided = true;
      readReflectance(d, "Kd", 0.25f, &b);
      b.specularReflectance = Spectrum(0.25f);
      getSpectrum(d, "Ks", &b.specularReflectance);
      double alpha = roughness(d, false, 0.1, true);
      if (!(alpha > 0)) fail(d, "plastic of roughness 0 (without remapping) is not supported");
      b.alpha = float(alpha);
      b.distribution = MicrofacetDistribution::GGX;
      b.intIOR = 1.5f;
      b.extIOR = 1.0f;
      warn(d,
           "plastic: its glossy lobe's Fresnel term is a dielectric's seen from the air (pbrt-v3 "
           "computes it from inside the coating, which reflects totally beyond 42 degrees)");
    } else if (type == "coateddiffuse") {
      // pbrt-v4's coateddiffuse: a dielectric coat over a Lambertian base, which pbrt evaluates
      // by a random walk between the two; here in closed form (bsdfs/coated_diffuse.h, with the
      // base's inter-reflections summed as their series, as the walk does).
      b.type = BsdfDescription::Type::CoatedDiffuse;
      b.twoSided = true;
      readReflectance(d, "reflectance", 0.5f, &b);
      const double eta = scalarIndex(d, d.params.find("eta"), 1.5);
      if (!(eta > 0) || eta > 100 || eta == 1)
        fail(d, what + ": the coat's index of refraction must be in (0, 100] and not 1");
      Spectrum albedo(0.0f);
      getSpectrum(d, "albedo", &albedo);
      if (!isBlack(albedo)) fail(d, what + ": a scattering coat (albedo > 0) is not supported");
      getFloat(d, "g", 0);
      getInt(d, "maxdepth", 10);  // the random walk's: the series here has no end
      getInt(d, "nsamples", 1);
      const double thickness = getFloat(d, "thickness", 0.01);
      if (!(thickness >= 0)) fail(d, what + ": thickness must be >= 0");
      const double alpha = roughness(d, true, 0.0);
      b.distribution = MicrofacetDistribution::GGX;
      b.alpha = alpha > 0 ? float(alpha) : 1e-4f;
      b.intIOR = float(eta);
      b.extIOR = 1.0f;
      b.nonlinear = true;
      b.specularReflectance = Spectrum(1.0f);
      finishCoatedDiffuse(d.file, d.line, what, &b);
      warn(d, what +
                  ": rendered in closed form, not by pbrt-v4's random walk; its layer absorbs "
                  "nothing here (pbrt's, of thickness " +
                  formatNumber(thickness) + ", does, slightly)" +
                  (alpha > 0 ? "" : "; its smooth coat is a microfacet coat of roughness 1e-4"));
    } else {
      fail(d, what +
                  " is not supported (matte/diffuse, metal/conductor, mirror, glass/dielectric, "
                  "plastic, coateddiffuse)");
    }
    getString(d, "type", "");  // MakeNamedMaterial's, read already
    rejectUnused(d, what);
    scene_.bsdfs.push_back(b);
    return int(scene_.bsdfs.size()) - 1;
  }

  int currentMaterial() {
    if (attrs_.material == -1) {
      if (defaultMaterial_ < 0) {
        BsdfDescription b;
        b.type = BsdfDescription::Type::Diffuse;
        b.twoSided = true;
        b.reflectance = Spectrum(0.5f);
        scene_.bsdfs.push_back(b);
        defaultMaterial_ = int(scene_.bsdfs.size()) - 1;
      }
      return defaultMaterial_;
    }
    return attrs_.material;
  }

  // ---- Lights ----

  void parseAreaLight(Directive& d) {
    if (d.strings[0] != "diffuse")
      fail(d, "area light '" + d.strings[0] + "' is not supported (diffuse)");
    Spectrum L(1.0f);
    getSpectrum(d, "L", &L);
    double scale = getFloat(d, "scale", 1);
    if (!(scale >= 0)) fail(d, "area light scale must be >= 0");
    attrs_.areaLight.twoSided = getBool(d, "twosided", false);
    if (d.params.has("power")) fail(d, "area light 'power' is not supported: give L");
    if (d.params.has("filename")) fail(d, "image area lights are not supported");
    getInt(d, "nsamples", 1);  // v3's sample count: the farm samples its own way
    getInt(d, "samples", 1);
    rejectUnused(d, "area light");
    attrs_.areaLight.radiance = L * float(scale);
    attrs_.areaLight.active = true;
  }

  // LightSource "infinite": the environment, constant or a lat-long image (v3's "mapname",
  // v4's "filename"), in the light's coordinate system (z up).
  // A "point3" parameter (v3 also writes "point"), in the light's coordinate system.
  Vec3f getPoint(Directive& d, const std::string& name, const Vec3f& def) {
    Param* p = typed(d, name, {"point3", "point"});
    if (!p) return def;
    if (p->numbers.size() != 3) failParam(d, *p, "parameter '" + name + "' takes 3 numbers");
    return Vec3f(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2]));
  }

  // LightSource "point" and "spot": intensity I (times scale) from "from", a spot aimed at "to"
  // with a cone of "coneangle" degrees whose last "conedeltaangle" (v4: "conedelta") fall off.
  void parsePointLight(Directive& d) {
    const std::string& type = d.strings[0];
    if (inObject_) fail(d, "a light source inside an object definition");
    PointLightDescription light;
    Spectrum I(1.0f), scale(1.0f);
    getSpectrum(d, "I", &I);
    getSpectrum(d, "scale", &scale);
    if (d.params.has("power")) fail(d, type + " light 'power' is not supported: give I");
    const Vec3f from = getPoint(d, "from", Vec3f(0.0f));
    light.position = attrs_.ctm.applyPoint(from);
    light.intensity = I * scale;
    if (type == "spot") {
      const Vec3f to = getPoint(d, "to", Vec3f(0, 0, 1));
      const double cone = getFloat(d, "coneangle", 30);
      double delta = getFloat(d, "conedeltaangle", 5);
      if (d.params.has("conedelta")) delta = getFloat(d, "conedelta", 5);
      if (!(cone > 0 && cone <= 180)) fail(d, "spot coneangle must be in (0, 180] degrees");
      if (!(delta >= 0 && delta <= cone)) fail(d, "spot cone delta must be in [0, coneangle]");
      const Vec3f axis = attrs_.ctm.applyVector(to - from);
      if (!(length(axis) > 0) || !isFinite(axis)) fail(d, "spot: \"from\" and \"to\" coincide");
      light.spot = true;
      light.direction = normalize(axis);
      light.cosTotalWidth = float(std::cos(cone * M_PI / 180));
      light.cosFalloffStart = float(std::cos((cone - delta) * M_PI / 180));
      light.falloff = PointLightDescription::Falloff::PbrtV3Quartic;  // v4's: at the end
    }
    rejectUnused(d, type + " light");
    if (!isFinite(light.position)) fail(d, type + " light: its position is not finite");
    light.origin =
        fs::path(d.file).filename().string() + ":" + std::to_string(d.line) + " (" + type + ")";
    scene_.pointLights.push_back(light);
  }

  void parseLightSource(Directive& d) {
    if (d.strings[0] == "point" || d.strings[0] == "spot") return parsePointLight(d);
    if (d.strings[0] != "infinite")
      fail(d, "light source '" + d.strings[0] +
                  "' is not supported yet (AreaLightSource \"diffuse\"; LightSource "
                  "\"infinite\", \"point\" and \"spot\")");
    if (scene_.environment.present) fail(d, "more than one infinite light");
    if (inObject_) fail(d, "a light source inside an object definition");
    Spectrum L(1.0f), scale(1.0f);
    getSpectrum(d, "L", &L);
    getSpectrum(d, "scale", &scale);
    std::string filename = getString(d, "filename", "");
    const std::string mapname = getString(d, "mapname", "");
    if (!filename.empty() && !mapname.empty()) fail(d, "both \"filename\" and \"mapname\" given");
    // v4's "filename" names a square equal-area map; a lat-long one (v3's "mapname") is taken too.
    const bool equalAreaAllowed = !filename.empty();
    if (filename.empty()) filename = mapname;
    if (d.params.has("illuminance")) fail(d, "infinite light 'illuminance' is not supported");
    if (d.params.has("portal")) fail(d, "infinite light portals are not supported");
    getInt(d, "nsamples", 1);  // v3's sample count: the farm samples its own way
    getInt(d, "samples", 1);
    rejectUnused(d, "infinite light");
    scene_.environment =
        makeEnvironment(dir_, d.file, d.line, L * scale, attrs_.ctm, filename, equalAreaAllowed);
  }

  // ---- Shapes ----

  // ---- Media ----

  int mediumNamed(const Directive& d, const std::string& name) {
    if (name.empty()) return -1;
    auto it = namedMedia_.find(name);
    if (it == namedMedia_.end()) fail(d, "medium '" + name + "' is not defined");
    return it->second;
  }

  // MakeNamedMedium: "homogeneous", or a density grid (pbrt-v3's "heterogeneous", pbrt-v4's
  // "uniformgrid": "density" with x fastest over nx * ny * nz values at cell centres, spanning
  // p0 to p1 in the space of the current transformation; pbrt-v4's "nanovdb" with the grid
  // "density" of an OpenVDB file, a .vdb: NanoVDB's own files are not read). sigma_a and
  // sigma_s are required: pbrt-v3 and v4 default them differently.
  int makeMedium(Directive& d) {
    const std::string type = getString(d, "type", "");
    const std::string what = "medium '" + d.strings[0] + "' of type '" + type + "'";
    if (type != "homogeneous" && type != "heterogeneous" && type != "uniformgrid" &&
        type != "nanovdb")
      fail(d, type.empty() ? "MakeNamedMedium '" + d.strings[0] + "' has no \"string type\""
                           : what +
                                 " is not supported (homogeneous, heterogeneous, uniformgrid, "
                                 "nanovdb with an OpenVDB file)");
    if (type == "uniformgrid" || type == "nanovdb") sawV4_ = true;
    if (d.params.has("preset"))
      failParam(d, *d.params.find("preset"),
                what +
                    ": named presets (measured coefficients) are not supported: give "
                    "sigma_a and sigma_s");
    for (const char* emission : {"Le", "Lescale", "temperature", "temperaturescale"})
      if (d.params.has(emission))
        failParam(d, *d.params.find(emission), what + ": emitting media are not supported");
    MediumDescription m;
    m.id = d.strings[0];
    m.origin = fs::path(d.file).filename().string() + ":" + std::to_string(d.line) + " (" + type +
               " '" + d.strings[0] + "')";
    if (!getSpectrum(d, "sigma_a", &m.sigmaA) || !getSpectrum(d, "sigma_s", &m.sigmaS))
      fail(d, what +
                  " needs \"rgb sigma_a\" and \"rgb sigma_s\" (pbrt-v3 and v4 default "
                  "them differently)");
    const double scale = getFloat(d, "scale", 1);
    if (!(scale >= 0) || !std::isfinite(scale)) fail(d, what + ": scale must be >= 0");
    m.sigmaA *= float(scale);
    m.sigmaS *= float(scale);
    m.g = float(getFloat(d, "g", 0));
    if (type == "nanovdb") {
      const std::string filename = getString(d, "filename", "");
      if (filename.empty()) fail(d, what + " needs a \"string filename\"");
      if (filename.size() < 5 || filename.substr(filename.size() - 4) != ".vdb")
        fail(d, what + ": '" + filename +
                    "' is not an OpenVDB file (.vdb); NanoVDB files are not read: convert it "
                    "with nanovdb_convert");
      const fs::path file = sceneFilePath(dir_, filename, "volume file", d.file, d.line);
      std::string problem;
      if (!readVdbDensity(file, "density", &m, &problem)) fail(d, filename + ": " + problem);
      const Matrix4 worldToMedium = attrs_.ctm.inverse();
      if (!worldToMedium.isFinite()) fail(d, what + ": the transformation is singular");
      m.worldToGrid = m.worldToGrid * worldToMedium;
    } else if (type != "homogeneous") {
      m.type = MediumDescription::Type::Grid;
      const long long nx = getInt(d, "nx", 1), ny = getInt(d, "ny", 1), nz = getInt(d, "nz", 1);
      if (nx < 1 || ny < 1 || nz < 1 || nx * ny > (1ll << 28) / nz)
        fail(d, what + ": nx, ny and nz must be >= 1 and their product at most 2^28");
      m.nx = int(nx), m.ny = int(ny), m.nz = int(nz);
      const std::vector<double> density = getNumbers(d, "density", {"float"}, 1);
      if (density.size() != size_t(nx * ny * nz))
        fail(d, what + ": \"float density\" has " + std::to_string(density.size()) +
                    " values for nx * ny * nz = " + std::to_string(nx * ny * nz));
      m.density.assign(density.begin(), density.end());
      const Vec3f p0 = getPoint(d, "p0", Vec3f(0.0f)), p1 = getPoint(d, "p1", Vec3f(1.0f));
      const Matrix4 gridToWorld = attrs_.ctm * Matrix4::translate(p0) * Matrix4::scale(p1 - p0);
      m.worldToGrid = gridToWorld.inverse();
      if (!m.worldToGrid.isFinite()) fail(d, what + ": the box from p0 to p1 is empty");
      m.cellCentred = true;
    }
    rejectUnused(d, what);
    const std::string problem = mediumProblem(m);
    if (!problem.empty()) fail(d, what + ": " + problem);
    scene_.media.push_back(std::move(m));
    return int(scene_.media.size()) - 1;
  }

  void parseShape(Directive& d) {
    const std::string& type = d.strings[0];
    const std::string what = "shape '" + type + "'";
    for (const char* alpha : {"alpha", "shadowalpha"}) {
      Param* p = d.params.find(alpha);
      if (p && (p->type == "texture" || p->numbers.size() != 1 || p->numbers[0] != 1))
        failParam(d, *p, what + ": alpha cut-outs are not supported");
    }
    ShapeDescription shape;
    shape.bsdf = currentMaterial();
    if (attrs_.areaLight.active && !isBlack(attrs_.areaLight.radiance)) {
      shape.isEmitter = true;
      shape.radiance = attrs_.areaLight.radiance;
      shape.emitsBothSides = attrs_.areaLight.twoSided;
    }
    if (shape.bsdf == kInterfaceMaterial) {
      if (shape.isEmitter) fail(d, what + ": an area light on an interface material");
      shape.nullBoundary = true;
      shape.bsdf = -1;
    }
    // pbrt: a shape changes the medium only where its two sides differ.
    if (attrs_.insideMedium != attrs_.outsideMedium) {
      shape.hasMediumInterface = true;
      shape.interiorMedium = mediumNamed(d, attrs_.insideMedium);
      shape.exteriorMedium = mediumNamed(d, attrs_.outsideMedium);
    }
    shape.origin =
        fs::path(d.file).filename().string() + ":" + std::to_string(d.line) + " (" + type;
    const Matrix4& toWorld = attrs_.ctm;
    const bool swaps = determinant3(toWorld) < 0;
    // Without shading normals, pbrt turns a triangle's normal (which follows its winding in
    // world space) round for ReverseOrientation and for a mirroring transform; with them the
    // geometric normal follows the shading normal and neither applies.
    const bool flipWithoutNormals = attrs_.reverseOrientation != swaps;
    const bool textured =
        shape.bsdf >= 0 && scene_.bsdfs[size_t(shape.bsdf)].reflectanceTexture >= 0;

    if (type == "trianglemesh" || type == "bilinearmesh") {
      const bool bilinear = type == "bilinearmesh";
      std::vector<double> P = getNumbers(d, "P", {"point3"}, 3);
      if (P.empty()) fail(d, what + " has no \"point3 P\"");
      const size_t nv = P.size() / 3;
      std::vector<double> idx = getNumbers(d, "indices", {"integer"}, bilinear ? 4 : 3);
      if (idx.empty()) {
        if (nv != (bilinear ? 4u : 3u)) fail(d, what + " has no \"integer indices\"");
        for (size_t k = 0; k < nv; ++k) idx.push_back(double(k));
      }
      std::vector<double> N = getNumbers(d, "N", {"normal3"}, 3);
      Param* uvParam = d.params.find("uv");
      if (!uvParam) uvParam = d.params.find("st");
      std::vector<double> uv;
      if (uvParam) {
        if ((uvParam->type != "float" && uvParam->type != "point2") ||
            uvParam->numbers.size() != 2 * nv)
          failParam(d, *uvParam, what + ": uv needs two numbers per vertex");
        uv = uvParam->numbers;
      }
      getNumbers(d, "S", {"vector3"}, 3);  // tangents: no anisotropic BSDF reads them
      getNumbers(d, "faceIndices", {"integer"}, 1);
      rejectUnused(d, what);
      if (!N.empty() && N.size() != P.size()) fail(d, what + ": N needs one normal per vertex");
      std::vector<Vec3f> positions(nv), normals;
      std::vector<Vec2f> uvs;
      for (size_t k = 0; k < nv; ++k) positions[k] = vec(P, 3 * k);
      if (!N.empty()) {
        normals.resize(nv);
        for (size_t k = 0; k < nv; ++k) normals[k] = vec(N, 3 * k);
      }
      if (!uv.empty()) {
        uvs.resize(nv);
        for (size_t k = 0; k < nv; ++k) uvs[k] = Vec2f(float(uv[2 * k]), float(uv[2 * k + 1]));
      }
      for (double v : idx)
        if (v < 0 || v >= double(nv) || v != std::floor(v))
          fail(d, what + ": index " + formatNumber(v) + " is not one of the " + std::to_string(nv) +
                      " vertices");
      if (bilinear) {
        // Patches p00 p10 p01 p11; a planar one is exactly two triangles.
        for (size_t q = 0; q < idx.size(); q += 4) {
          const Vec3f &p00 = positions[size_t(idx[q])], &p10 = positions[size_t(idx[q + 1])],
                      &p01 = positions[size_t(idx[q + 2])], &p11 = positions[size_t(idx[q + 3])];
          Vec3f n = cross(p10 - p00, p01 - p00);
          float scale = std::max({length(p10 - p00), length(p01 - p00), length(p11 - p00)});
          if (std::fabs(dot(normalize(n), p11 - p00)) > 1e-5f * scale)
            fail(d, what + ": a non-planar bilinear patch is not supported");
          uint32_t a = uint32_t(idx[q]), b = uint32_t(idx[q + 1]), c = uint32_t(idx[q + 2]),
                   e = uint32_t(idx[q + 3]);
          for (uint32_t v : {a, b, e, a, e, c}) shape.indices.push_back(v);
        }
        if (uvs.empty()) {
          // pbrt's default patch parameterization: (0,0) (1,0) (0,1) (1,1) per patch corner;
          // only well defined when patches do not share vertices, so only for textures that
          // need it.
          if (textured) fail(d, what + ": a textured bilinear patch needs uv");
        }
      } else {
        for (double v : idx) shape.indices.push_back(uint32_t(v));
      }
      if (textured && uvs.empty()) {
        // pbrt's default triangle uvs are (0,0) (1,0) (1,1) per triangle: meshes sharing
        // vertices cannot carry them, and a texture read at one point would be a constant.
        fail(d, what + " has a textured material but no uv");
      }
      const bool hasNormals = !normals.empty();
      if (hasNormals && flipWithoutNormals) warnOrientation(d);
      finishMesh(d.file, d.line, what, toWorld, !hasNormals,
                 hasNormals ? false : flipWithoutNormals, std::move(positions), std::move(normals),
                 std::move(uvs), &shape, &scene_.warnings);
      shape.origin += ")";
    } else if (type == "plymesh") {
      std::string filename = getString(d, "filename", "");
      if (filename.empty()) fail(d, what + " has no filename");
      if (d.params.has("displacement")) fail(d, what + ": displacement is not supported");
      getFloat(d, "edgelength", 1);
      rejectUnused(d, what);
      const fs::path path = sceneFilePath(dir_, filename, "mesh file", d.file, d.line);
      PlyMesh mesh;
      auto cached = plyCache_.find(path.lexically_normal().string());
      if (cached != plyCache_.end()) {
        mesh = cached->second;
      } else {
        const std::string bytes = readSceneFile(path, "PLY '" + filename + "'", d.file, d.line);
        try {
          mesh = parsePly(bytes);
        } catch (const std::exception& e) {
          fail(d, "cannot read PLY '" + filename + "': " + e.what());
        }
        plyCache_[path.lexically_normal().string()] = mesh;
      }
      if (textured && mesh.uvs.empty())
        fail(d, what + " '" + filename + "' has a textured material but no texture coordinates");
      shape.indices = std::move(mesh.indices);
      const bool hasNormals = !mesh.normals.empty();
      if (hasNormals && flipWithoutNormals) warnOrientation(d);
      finishMesh(d.file, d.line, "PLY '" + filename + "'", toWorld, !hasNormals,
                 hasNormals ? false : flipWithoutNormals, std::move(mesh.positions),
                 std::move(mesh.normals), std::move(mesh.uvs), &shape, &scene_.warnings);
      shape.origin += " " + filename + ")";
    } else if (type == "sphere") {
      double r = getFloat(d, "radius", 1);
      if (!(r > 0)) fail(d, "sphere radius must be > 0");
      double zmin = getFloat(d, "zmin", -r), zmax = getFloat(d, "zmax", r);
      double phimax = getFloat(d, "phimax", 360);
      if (zmin > -r || zmax < r || phimax < 360) fail(d, "partial spheres are not supported");
      rejectUnused(d, what);
      if (textured) fail(d, "textured spheres are not supported");
      double s = similarityScale(d, toWorld);
      shape.type = ShapeDescription::Type::Sphere;
      shape.center = toWorld.applyPoint(Vec3f(0.0f));
      shape.radius = float(r * s);
      shape.flipNormals = flipWithoutNormals;
      if (!(shape.radius > 0) || !std::isfinite(shape.radius) || !isFinite(shape.center))
        fail(d, "sphere has a degenerate world-space radius or center");
      shape.origin += ")";
    } else if (type == "disk") {
      double h = getFloat(d, "height", 0), r = getFloat(d, "radius", 1);
      double inner = getFloat(d, "innerradius", 0), phimax = getFloat(d, "phimax", 360);
      if (!(r > 0)) fail(d, "disk radius must be > 0");
      if (inner != 0 || phimax < 360) fail(d, "partial disks (annuli, sectors) are not supported");
      rejectUnused(d, what);
      // A fan of kDiskSegments triangles, normal +z, pbrt's uv: u = phi / 2 pi, v = 1 - r / R.
      std::vector<Vec3f> positions;
      std::vector<Vec2f> uvs;
      for (int k = 0; k < kDiskSegments; ++k) {
        double p0 = 2 * kPi * k / kDiskSegments, p1 = 2 * kPi * (k + 1) / kDiskSegments;
        uint32_t base = uint32_t(positions.size());
        positions.emplace_back(0.0f, 0.0f, float(h));
        positions.emplace_back(float(r * std::cos(p0)), float(r * std::sin(p0)), float(h));
        positions.emplace_back(float(r * std::cos(p1)), float(r * std::sin(p1)), float(h));
        uvs.emplace_back(float((k + 0.5) / kDiskSegments), 1.0f);
        uvs.emplace_back(float(double(k) / kDiskSegments), 0.0f);
        uvs.emplace_back(float(double(k + 1) / kDiskSegments), 0.0f);
        for (uint32_t v = 0; v < 3; ++v) shape.indices.push_back(base + v);
      }
      finishMesh(d.file, d.line, what, toWorld, true, flipWithoutNormals, std::move(positions), {},
                 std::move(uvs), &shape, &scene_.warnings);
      warn(d, "disk tessellated into " + std::to_string(kDiskSegments) +
                  " triangles (area 6e-6 short of the disk's)");
      shape.origin += ")";
    } else {
      fail(d, what + " is not supported (trianglemesh, plymesh, sphere, disk, bilinearmesh)");
    }
    // A scene-wide budget: a small file can name a large PLY many times, or many disks.
    geometryElements_ += shape.positions.size() + shape.indices.size();
    if (geometryElements_ > kMaxGeometryElements)
      fail(d, "the scene's meshes exceed " + std::to_string(kMaxGeometryElements) +
                  " vertices and triangle corners in all");
    if (inObject_) {
      // Instanced shapes take no area light (pbrt refuses them too: one light per instance
      // would need the instance's transform in its sampling).
      if (shape.isEmitter) fail(d, "an area light inside an object definition is not supported");
      objects_[objectName_].push_back(std::move(shape));
      return;
    }
    scene_.shapes.push_back(std::move(shape));
  }

  // ObjectInstance: the object's shapes (in the space their definition's transformation made)
  // copied through the current transformation, as pbrt's instance-to-world applies it to them.
  void instantiate(Directive& d) {
    if (inObject_) fail(d, "ObjectInstance inside the definition of object '" + objectName_ + "'");
    auto it = objects_.find(d.strings[0]);
    if (it == objects_.end()) fail(d, "object '" + d.strings[0] + "' is not defined");
    const Matrix4& m = attrs_.ctm;
    if (std::fabs(determinant3(m)) < 1e-30 || !m.inverse().isFinite())
      fail(d, "the instance's transformation is singular");
    const Matrix4 normalMatrix = m.inverse().transpose();
    const bool mirrors = determinant3(m) < 0;
    for (const ShapeDescription& original : it->second) {
      ShapeDescription shape = original;
      shape.origin +=
          " instanced at " + fs::path(d.file).filename().string() + ":" + std::to_string(d.line);
      if (shape.type == ShapeDescription::Type::Sphere) {
        shape.center = m.applyPoint(shape.center);
        // The instance's transformation moves normals by its inverse transpose, which keeps them
        // on their side even under a mirror: orientation is the definition's (as in pbrt).
        shape.radius = float(shape.radius * similarityScale(d, m));
      } else {
        for (Vec3f& p : shape.positions) p = m.applyPoint(p);
        for (Vec3f& n : shape.normals) {
          n = normalize(normalMatrix.applyVector(n));
          if (!isFinite(n)) fail(d, "the instance's transformation makes a normal non-finite");
        }
        // Without normals the winding tells the outside: a mirror would turn it round.
        if (mirrors)
          for (size_t t = 0; t < shape.indices.size(); t += 3)
            std::swap(shape.indices[t + 1], shape.indices[t + 2]);
        for (const Vec3f& p : shape.positions)
          if (!isFinite(p)) fail(d, "the instance's transformation makes a position non-finite");
      }
      geometryElements_ += shape.positions.size() + shape.indices.size();
      if (geometryElements_ > kMaxGeometryElements)
        fail(d, "the scene's meshes exceed " + std::to_string(kMaxGeometryElements) +
                    " vertices and triangle corners in all");
      scene_.shapes.push_back(std::move(shape));
    }
  }

  // pbrt-v3 turns a mesh with normals round under ReverseOrientation (or a mirror), v4 does not:
  // the farm follows v4 (the normals decide) and says so, as it decides where a light shines.
  void warnOrientation(const Directive& d) {
    warn(d,
         "mesh with normals under ReverseOrientation or a mirroring transform: oriented by its "
         "normals, as pbrt-v4 does (pbrt-v3 would turn it round)");
  }

  // The uniform scale of a rotation-scale-translation matrix: spheres stay analytic.
  double similarityScale(const Directive& d, const Matrix4& t) const {
    double s;
    switch (similarityOf(t, &s)) {
      case Similarity::NonUniformScale:
        fail(d, "a sphere under a non-uniform scale (an ellipsoid) is not supported");
      case Similarity::Shear:
        fail(d, "a sphere under a shear is not supported");
      case Similarity::Uniform:
        break;
    }
    return s;
  }

  std::string path_;
  fs::path dir_;
  SceneDescription scene_;
  bool sawWorld_ = false, sawCamera_ = false, inObject_ = false;
  std::string objectName_;
  size_t objectBlockDepth_ = 0;    // the attribute stack's size inside the definition's block
  bool gaussianDefaults_ = false;  // a parameterless gaussian: v3's or v4's, known at the end
  std::map<std::string, std::vector<ShapeDescription>> objects_;
  Attributes attrs_;
  std::vector<Attributes> attributeStack_;
  std::vector<Matrix4> transformStack_;
  std::map<std::string, Matrix4> namedCoordinateSystems_;
  std::map<std::string, int> namedMaterials_;
  std::map<std::string, int> namedMedia_;
  std::string cameraMedium_, cameraDirectiveFile_;
  int cameraDirectiveLine_ = 0;
  std::map<std::string, NamedTexture> spectrumTextures_, floatTextures_;
  TextureImageCache images_;
  std::vector<int> textureDepth_;  // per texture: 1 + its deepest child's
  size_t geometryElements_ = 0;
  int includedFiles_ = 0;
  std::vector<std::string> includeStack_;
  bool sawFilter_ = false, sawV4_ = false;
  std::map<std::string, PlyMesh> plyCache_;
  int defaultMaterial_ = -1;
};

}  // namespace

SceneDescription loadPbrtScene(const std::string& path) {
  return PbrtLoader(path).load();
}

}  // namespace farm
