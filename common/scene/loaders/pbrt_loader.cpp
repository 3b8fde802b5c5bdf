#include "common/scene/loaders/pbrt_loader.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>
#include <utility>
#include <vector>

#include "common/scene/loaders/camera_builders.h"
#include "common/scene/loaders/image_reader.h"
#include "common/scene/loaders/light_builders.h"
#include "common/scene/loaders/material_builders.h"
#include "common/scene/loaders/medium_builders.h"
#include "common/scene/loaders/pbrt_parser.h"
#include "common/scene/loaders/ply_reader.h"
#include "common/scene/loaders/vdb_reader.h"
#include "common/scene/medium.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr int kDiskSegments = 1024;  // area deficit (2 pi / n)^2 / 6 = 6e-6 of the disk's

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
constexpr size_t kMaxGeometryElements = size_t(1) << 28;  // vertices + triangle corners

class PbrtLoader : public PbrtTarget {
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
    parsePbrt(path_, text, this);
    // pbrt-v4's default filter is a gaussian of radius 1.5 and sigma 0.5; v3's a box.
    if (sawV4_ && (!sawFilter_ || gaussianDefaults_)) setGaussianFilter(&scene_.camera, 1.5, 2);
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
  // ---- Errors ----

  void warn(const PbrtDirective& d, const std::string& what) {
    scene_.warnings.push_back(formatLoadMessage(d.file, d.line, what));
  }

  // ---- Typed parameter access ----

  // An RGB (or named metal) spectrum; `isTexture` tells whether a "texture" reference is
  // allowed here (then *texture receives its index and the spectrum is unused).
  bool getSpectrum(PbrtDirective& d, const std::string& name, Spectrum* out,
                   int* texture = nullptr) {
    PbrtParam* p = d.find(name);
    if (!p) return false;
    if (p->type == "texture") {
      if (!texture) d.failParam(*p, "parameter '" + name + "' cannot be a texture here");
      if (p->strings.size() != 1) d.failParam(*p, "parameter '" + name + "' names one texture");
      *texture = useTexture(d, *p, p->strings[0], false);
      return true;
    }
    if (p->type == "rgb") {
      if (p->numbers.size() != 3) d.failParam(*p, "rgb parameter '" + name + "' takes 3 numbers");
      for (double v : p->numbers)
        if (v < 0) d.failParam(*p, "rgb parameter '" + name + "' is negative");
      *out = Spectrum(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2]));
      return true;
    }
    if (p->type == "float") {
      if (p->numbers.size() != 1) d.failParam(*p, "parameter '" + name + "' takes one number");
      if (p->numbers[0] < 0) d.failParam(*p, "parameter '" + name + "' is negative");
      *out = Spectrum(float(p->numbers[0]));
      return true;
    }
    if (p->type == "spectrum") {
      if (p->strings.size() == 1) {
        const std::string& s = p->strings[0];
        for (const MetalIndex& m : pbrtNamedMetals()) {
          const std::string prefix = std::string("metal-") + m.name + "-";
          if (s == prefix + "eta") return *out = m.eta, true;
          if (s == prefix + "k") return *out = m.k, true;
        }
        d.failParam(*p, "spectrum '" + s +
                            "' is not supported (named spectra: metal-{Ag,Al,Au,Cu,CuZn,MgO,"
                            "TiO2}-{eta,k}); give it as rgb");
      }
      d.failParam(*p, "sampled spectrum '" + name + "' is not supported: give it as rgb");
    }
    if (p->type == "blackbody")
      d.failParam(*p, "blackbody spectrum '" + name + "' is not supported: give it as rgb");
    d.failParam(*p, "parameter '" + name + "' must be an rgb spectrum, not " + p->type);
  }

  // ---- What the parser hands over ----

  void directive(PbrtDirective& d) override { apply(d); }
  void included(const PbrtDirective& d) override {
    if (d.name == "Import") sawV4_ = true;  // pbrt-v4's
  }

  // ---- Directives ----

  void apply(PbrtDirective& d) {
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
        d.fail("color space '" + d.strings[0] + "' is not supported (srgb only)");
    } else if (n == "Option") {
      d.fail("Option is not supported");
    } else if (n == "WorldBegin") {
      if (sawWorld_) d.fail("a second WorldBegin");
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
      std::string type = d.getString("type", "");
      if (type.empty()) d.fail("MakeNamedMaterial '" + d.strings[0] + "' has no \"string type\"");
      namedMaterials_[d.strings[0]] = makeMaterial(d, type);
    } else if (n == "NamedMaterial") {
      inWorld(d);
      auto it = namedMaterials_.find(d.strings[0]);
      if (it == namedMaterials_.end())
        d.fail("named material '" + d.strings[0] + "' is not defined");
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
      if (namedMedia_.count(d.strings[0])) d.fail("medium '" + d.strings[0] + "' is defined twice");
      namedMedia_[d.strings[0]] = makeMedium(d);
    } else if (n == "MediumInterface") {
      // One name: the same medium on both sides; two: inside, then outside.
      if (d.strings.empty()) d.fail("MediumInterface names one or two media");
      attrs_.insideMedium = d.strings[0];
      attrs_.outsideMedium = d.strings.size() > 1 ? d.strings[1] : d.strings[0];
    } else if (n == "ObjectBegin") {
      inWorld(d);
      if (inObject_) d.fail("ObjectBegin inside the definition of object '" + objectName_ + "'");
      if (objects_.count(d.strings[0])) d.fail("object '" + d.strings[0] + "' is defined twice");
      // As pbrt: an attribute block around the definition.
      attributeStack_.push_back(attrs_);
      objectBlockDepth_ = attributeStack_.size();
      inObject_ = true;
      objectName_ = d.strings[0];
      objects_[objectName_];
    } else if (n == "ObjectEnd") {
      if (!inObject_) d.fail("ObjectEnd without ObjectBegin");
      if (attributeStack_.size() != objectBlockDepth_)
        d.fail("ObjectEnd inside an AttributeBegin that the object's definition opened");
      inObject_ = false;
      attrs_ = attributeStack_.back();
      attributeStack_.pop_back();
    } else if (n == "ObjectInstance") {
      inWorld(d);
      instantiate(d);
    } else if (n == "Attribute") {
      d.fail("Attribute (default parameters) is not supported");
    } else {
      d.fail("unknown directive '" + n + "'");
    }
  }

  void beforeWorld(const PbrtDirective& d) const {
    if (sawWorld_) d.fail(d.name + " must come before WorldBegin");
  }
  void inWorld(const PbrtDirective& d) const {
    if (!sawWorld_) d.fail(d.name + " must come after WorldBegin");
  }

  void needNumbers(const PbrtDirective& d, size_t count) const {
    if (d.numbers.size() != count)
      d.fail(d.name + " takes " + std::to_string(count) + " numbers, not " +
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

  void applyTransformDirective(PbrtDirective& d) {
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
      if (!(length(axis) > 0)) d.fail("Rotate about a zero axis");
      ctm = ctm * Matrix4::rotate(axis, d.numbers[0]);
    } else if (n == "LookAt") {
      needNumbers(d, 9);
      // pbrt's LookAt is the inverse of the camera-to-world matrix Matrix4::lookAt builds: both
      // take right = up x dir.
      Matrix4 cameraToWorld =
          Matrix4::lookAt(vec(d.numbers, 0), vec(d.numbers, 3), vec(d.numbers, 6));
      if (!cameraToWorld.isFinite())
        d.fail("LookAt with the up vector along the view direction (or eye at the target)");
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
        d.fail("coordinate system '" + d.strings[0] + "' is not defined");
      ctm = it->second;
    } else if (n == "ReverseOrientation") {
      attrs_.reverseOrientation = !attrs_.reverseOrientation;
    } else if (n == "TransformBegin") {
      transformStack_.push_back(ctm);
    } else if (n == "TransformEnd") {
      if (transformStack_.empty()) d.fail("TransformEnd without TransformBegin");
      ctm = transformStack_.back();
      transformStack_.pop_back();
    } else if (n == "AttributeBegin") {
      attributeStack_.push_back(attrs_);
    } else if (n == "AttributeEnd") {
      if (attributeStack_.empty()) d.fail("AttributeEnd without AttributeBegin");
      if (inObject_ && attributeStack_.size() <= objectBlockDepth_)
        d.fail("AttributeEnd would end the definition of object '" + objectName_ +
               "' (it needs ObjectEnd)");
      attrs_ = attributeStack_.back();
      attributeStack_.pop_back();
    } else if (n == "ActiveTransform") {
      if (d.strings[0] != "All")
        d.fail("ActiveTransform " + d.strings[0] + ": motion blur is not supported");
    } else {  // TransformTimes
      d.fail("TransformTimes: motion blur is not supported");
    }
    if (!ctm.isFinite()) d.fail("the transformation is not finite (a zero scale?)");
  }

  // ---- Camera, film, filter, integrator ----

  void parseCamera(PbrtDirective& d) {
    if (sawCamera_) d.fail("a second Camera");
    sawCamera_ = true;
    // pbrt: the camera sits in the current outside medium.
    cameraMedium_ = attrs_.outsideMedium;
    cameraDirectiveFile_ = d.file;
    cameraDirectiveLine_ = d.line;
    if (d.strings[0] != "perspective")
      d.fail("camera '" + d.strings[0] + "' is not supported (perspective only)");
    double fov = d.getFloat("fov", 90);
    if (!(fov > 0 && fov < 180)) d.fail("fov must be in (0, 180) degrees");
    double lensRadius = d.getFloat("lensradius", 0);
    double focusDistance = d.getFloat("focaldistance", 1e6);
    if (!(lensRadius >= 0)) d.fail("lensradius must be >= 0");
    if (!(focusDistance > 0)) d.fail("focaldistance must be > 0");
    d.getFloat("shutteropen", 0);
    d.getFloat("shutterclose", 1);
    d.rejectUnused("Camera");
    // The CTM is world-to-camera. pbrt's camera space has +x to the image's right; ours (as
    // Mitsuba's) to the left, hence the mirror.
    const Matrix4 cameraToWorld = attrs_.ctm.inverse();
    if (!cameraToWorld.isFinite()) d.fail("the camera transformation is singular");
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
        d.fail("the camera transformation has a shear");
    // pbrt scales its rays' directions by it: a non-uniform scale would stretch the view.
    float lengths[3];
    for (int j = 0; j < 3; ++j)
      lengths[j] = length(cameraToWorld.applyVector(Vec3f(j == 0, j == 1, j == 2)));
    if (std::fabs(lengths[0] - lengths[1]) > 1e-4f * lengths[2] ||
        std::fabs(lengths[1] - lengths[2]) > 1e-4f * lengths[2])
      d.fail("the camera transformation has a non-uniform scale");
    scene_.camera.fovDegrees = float(fov);
    // Lens radius and focus distance are in camera space: to world units by the (uniform)
    // scale of the camera's transformation.
    const double scale = (double(lengths[0]) + lengths[1] + lengths[2]) / 3;
    scene_.camera.lensRadius = float(lensRadius * scale);
    scene_.camera.focusDistance = float(focusDistance * scale);
    scene_.camera.fovAxis = FovAxis::Smaller;  // pbrt's fov spans the shorter image axis
  }

  void parseFilm(PbrtDirective& d) {
    const std::string& type = d.strings[0];
    if (type != "image" && type != "rgb" && type != "gbuffer")
      d.fail("film '" + type + "' is not supported (image, rgb)");
    long long w = d.getInt("xresolution", 1280), h = d.getInt("yresolution", 720);
    if (w < 1 || h < 1 || w > kMaxFilmSide || h > kMaxFilmSide)
      d.fail("film resolution " + std::to_string(w) + "x" + std::to_string(h) +
             " is outside 1..65536");
    if (w * h > kMaxFilmPixels) d.fail("film of more than 2^28 pixels");
    d.getString("filename", "");  // the farm names its own output
    d.rejectUnused("Film");
    scene_.camera.width = int(w);
    scene_.camera.height = int(h);
  }

  void parseFilter(PbrtDirective& d) {
    sawFilter_ = true;
    const std::string& type = d.strings[0];
    // v3 names the radius "xwidth", v4 "xradius".
    auto radius = [&](const char* axis, double def) {
      std::string v3 = std::string(axis) + "width", v4 = std::string(axis) + "radius";
      double r = d.getFloat(v3, def);
      return d.getFloat(v4, r);
    };
    if (type == "box") {
      double rx = radius("x", 0.5), ry = radius("y", 0.5);
      if (rx != 0.5 || ry != 0.5) d.fail("box filter of radius other than 0.5 is not supported");
      scene_.camera.filter = FilterType::Box;
    } else if (type == "triangle") {
      double rx = radius("x", 2), ry = radius("y", 2);
      if (rx != 1 || ry != 1)
        d.fail("triangle filter of radius " + std::to_string(rx) + " x " + std::to_string(ry) +
               " is not supported (radius 1 only)");
      scene_.camera.filter = FilterType::Tent;
    } else if (type == "gaussian") {
      // v3: xwidth (2) and alpha (2); v4: xradius (1.5) and sigma (0.5), alpha = 1 / (2 sigma^2).
      const bool v4 = d.has("xradius") || d.has("yradius") || d.has("sigma");
      // Without parameters the version decides the radius (v3's 2, v4's 1.5): settled at the
      // end, when the file's materials have told it.
      gaussianDefaults_ = d.params.empty();
      const double rx = radius("x", v4 ? 1.5 : 2), ry = radius("y", v4 ? 1.5 : 2);
      if (rx != ry) d.fail("a gaussian filter with different x and y radii is not supported");
      // Below half a pixel some film points would reach no pixel centre.
      if (!(rx >= 0.5 && rx <= 16)) d.fail("gaussian filter radius must be in [0.5, 16] pixels");
      double alpha = d.getFloat("alpha", 2);
      if (d.has("sigma")) {
        const double sigma = d.getFloat("sigma", 0.5);
        if (!(sigma > 0)) d.fail("gaussian sigma must be > 0");
        alpha = 1 / (2 * sigma * sigma);
      }
      if (!(alpha >= 0.01 && alpha <= 100)) d.fail("gaussian alpha must be in [0.01, 100]");
      setGaussianFilter(&scene_.camera, rx, alpha);
    } else {
      d.fail("pixel filter '" + type +
             "' is not supported (box of radius 0.5, triangle of radius 1, gaussian)");
    }
    d.rejectUnused("PixelFilter");
  }

  void parseIntegrator(PbrtDirective& d) {
    static const char* const kUnbiased[] = {"path",       "volpath",   "bdpt",
                                            "mlt",        "sppm",      "simplepath",
                                            "randomwalk", "lightpath", "simplevolpath"};
    const std::string& type = d.strings[0];
    bool ok = false;
    for (const char* t : kUnbiased) ok = ok || type == t;
    if (!ok)
      d.fail("integrator '" + type +
             "' is not supported: its picture is not the light transport the farm renders");
    long long depth = d.getInt("maxdepth", 5);
    if (depth < 0) d.fail("maxdepth must be >= 0");
    if (depth > 100000) d.fail("maxdepth is absurdly large");
    // pbrt counts bounces (0: emitted light only); the farm counts edges, as Mitsuba does.
    scene_.maxDepth = int(depth) + 1;
    std::string ignored;
    for (PbrtParam& p : d.params)
      if (!p.used) {
        p.used = true;
        ignored += (ignored.empty() ? "" : ", ") + p.name;
      }
    if (!ignored.empty())
      warn(d,
           "integrator parameters ignored (the farm's settings choose the algorithm): " + ignored);
  }

  // ---- Textures ----

  void defineTexture(PbrtDirective& d) {
    const std::string& kind = d.strings[1];
    if (kind != "spectrum" && kind != "color" && kind != "float")
      d.fail("texture type '" + kind + "' must be spectrum or float");
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
  int useTexture(const PbrtDirective& user, const PbrtParam& p, const std::string& name,
                 bool isFloat) {
    auto& table = isFloat ? floatTextures_ : spectrumTextures_;
    auto it = table.find(name);
    if (it == table.end()) {
      auto& other = isFloat ? spectrumTextures_ : floatTextures_;
      if (other.count(name))
        user.failParam(p, std::string(isFloat ? "spectrum" : "float") + " texture '" + name +
                              "' used where a " + (isFloat ? "float" : "spectrum") +
                              " texture is needed");
      user.failParam(p, "texture '" + name + "' is not defined");
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
  int textureArgument(PbrtDirective& d, const std::string& name, bool isFloat, float def) {
    PbrtParam* p = d.find(name);
    if (!p) return constantTexture(Spectrum(def));
    if (p->type == "texture") {
      if (p->strings.size() != 1) d.failParam(*p, "parameter '" + name + "' names one texture");
      return useTexture(d, *p, p->strings[0], isFloat);
    }
    p->used = false;
    Spectrum v;
    getSpectrum(d, name, &v);
    return constantTexture(v);
  }

  void readMapping(PbrtDirective& d, TextureDescription* t) {
    std::string mapping = d.getString("mapping", "uv");
    if (mapping != "uv") d.fail("texture mapping '" + mapping + "' is not supported (uv only)");
    t->uScale = float(d.getFloat("uscale", 1));
    t->vScale = float(d.getFloat("vscale", 1));
    t->uOffset = float(d.getFloat("udelta", 0));
    t->vOffset = float(d.getFloat("vdelta", 0));
  }

  int buildTexture(PbrtDirective& d, bool isFloat) {
    const std::string& cls = d.strings[2];
    const std::string what = "texture '" + d.strings[0] + "' (" + cls + ")";
    TextureDescription t;
    t.origin =
        fs::path(d.file).filename().string() + ":" + std::to_string(d.line) + " (" + cls + ")";
    int result;
    if (cls == "imagemap") {
      if (isFloat) d.fail("float image textures are not supported (only reflectance is textured)");
      std::string filename = d.getString("filename", "");
      if (filename.empty()) d.fail(what + " has no filename");
      std::string wrap = d.getString("wrap", "repeat");
      if (wrap == "repeat")
        t.wrap = TextureWrap::Repeat;
      else if (wrap == "clamp")
        t.wrap = TextureWrap::Clamp;
      else if (wrap == "black")
        t.wrap = TextureWrap::Black;
      else
        d.fail("texture wrap '" + wrap + "' is not supported (repeat, clamp, black)");
      TextureEncoding encoding = TextureEncoding::Automatic;
      if (d.has("gamma"))
        encoding = d.getBool("gamma", false) ? TextureEncoding::SRGB : TextureEncoding::Linear;
      if (d.has("encoding")) {
        std::string e = d.getString("encoding", "sRGB");
        if (e == "sRGB")
          encoding = TextureEncoding::SRGB;
        else if (e == "linear")
          encoding = TextureEncoding::Linear;
        else
          d.fail("texture encoding '" + e + "' is not supported (sRGB, linear)");
      }
      if (d.getBool("invert", false)) d.fail("inverted image textures are not supported");
      double scale = d.getFloat("scale", 1);
      if (!(scale >= 0)) d.fail("texture scale must be >= 0");
      bool trilinear = d.getBool("trilinear", false);
      std::string filter = d.getString("filter", "bilinear");
      d.getFloat("maxanisotropy", 8);
      if (trilinear || (filter != "bilinear" && filter != "point"))
        warn(d, what +
                    ": filtered bilinearly (no MIP map); the pixel filter and the samples "
                    "average the texture over each pixel");
      readMapping(d, &t);
      d.rejectUnused(what);
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
      if (d.getInt("dimension", 2) != 2) d.fail("3D checkerboards are not supported");
      std::string aa = d.getString("aamode", "closedform");
      if (aa != "none")
        warn(d, what +
                    ": not antialiased by a closed form; the pixel filter and the samples "
                    "average it over each pixel");
      t.tex1 = textureArgument(d, "tex1", isFloat, 1);
      t.tex2 = textureArgument(d, "tex2", isFloat, 0);
      readMapping(d, &t);
      d.rejectUnused(what);
      t.type = TextureDescription::Type::Checkerboard;
      result = addTexture(std::move(t));
    } else if (cls == "scale") {
      // v3: tex1 * tex2; v4: tex * scale (a float).
      if (d.has("tex") || d.has("scale")) {
        t.tex1 = textureArgument(d, "tex", isFloat, 1);
        t.tex2 = textureArgument(d, "scale", true, 1);
      } else {
        t.tex1 = textureArgument(d, "tex1", isFloat, 1);
        t.tex2 = textureArgument(d, "tex2", isFloat, 1);
      }
      d.rejectUnused(what);
      t.type = TextureDescription::Type::Scale;
      result = addTexture(std::move(t));
    } else if (cls == "constant") {
      Spectrum v(1.0f);
      getSpectrum(d, "value", &v);
      d.rejectUnused(what);
      result = constantTexture(v);
    } else {
      d.fail("texture class '" + cls +
             "' is not supported (imagemap, checkerboard, scale, constant)");
    }
    return result;
  }

  // ---- Materials ----

  // Roughness of a (rough) conductor or dielectric as alpha, or 0 for a smooth one. v3's
  // materials remap with a polynomial, v4's with a square root; both have remaproughness.
  double roughness(PbrtDirective& d, bool v4, double def, bool metalV3 = false) {
    for (const char* name : {"roughness", "uroughness", "vroughness"}) {
      PbrtParam* p = d.find(name);
      if (p && p->type == "texture") d.failParam(*p, "textured roughness is not supported");
      if (p) p->used = false;
    }
    double r = d.getFloat("roughness", def);
    double u = d.getFloat("uroughness", r), v = d.getFloat("vroughness", r);
    if (u != v) d.fail("anisotropic roughness (uroughness != vroughness) is not supported");
    if (!(u >= 0)) d.fail("roughness must be >= 0");
    bool remap = d.getBool("remaproughness", true);
    double alpha = remap ? (v4 ? std::sqrt(u) : roughnessToAlphaV3(u)) : u;
    // pbrt-v4 renders microfacets of alpha below 1e-3 as smooth. v3 remaps roughness 0 to
    // its clamp 1e-3 (alpha 0.047) for metal, and has a smooth path for glass only.
    if (v4 ? alpha < 1e-3 : (alpha == 0 || (u == 0 && !metalV3))) return 0;
    return alpha;
  }

  // An index of refraction given as one float (`def` without the parameter); a spectral one is
  // refused.
  double scalarIndex(PbrtDirective& d, const PbrtParam* eta, double def) {
    if (!eta) return def;
    if (eta->type != "float" || eta->numbers.size() != 1)
      d.failParam(*eta,
                  "a dispersive (spectral) index of refraction is not supported: give one float");
    return eta->numbers[0];
  }

  // A diffuse reflectance, which may be a texture (`def` where the material does not give it):
  // diffuseMaterial's.
  BsdfDescription readDiffuse(PbrtDirective& d, const std::string& name, float def) {
    Spectrum reflectance(def);
    int texture = -1;
    getSpectrum(d, name, &reflectance, &texture);
    return diffuseMaterial(reflectance, texture);
  }

  int makeMaterial(PbrtDirective& d, const std::string& type) {
    if (type == "" || type == "none" || type == "interface") {
      d.getString("type", "");  // MakeNamedMaterial's, read already
      d.rejectUnused("material '" + type + "'");
      return kInterfaceMaterial;
    }
    if (type == "diffuse" || type == "conductor" || type == "dielectric" || type == "coateddiffuse")
      sawV4_ = true;
    const std::string what = "material '" + type + "'";
    for (const char* bump : {"bumpmap", "displacement"})
      if (d.has(bump))
        d.failParam(*d.find(bump), what + ": bump and displacement maps are not supported");
    BsdfDescription b;
    if (type == "matte" || type == "diffuse") {
      b = readDiffuse(d, type == "matte" ? "Kd" : "reflectance", 0.5f);
      if (type == "matte" && d.getFloat("sigma", 0) != 0)
        d.fail("Oren-Nayar matte (sigma > 0) is not supported");
    } else if (type == "metal" || type == "conductor") {
      const bool v4 = type == "conductor";
      if (v4 && d.has("reflectance"))
        d.fail("conductor given by reflectance is not supported: give eta and k");
      const MetalIndex& copper = *pbrtNamedMetal("Cu");  // both versions' default
      Spectrum eta = copper.eta, k = copper.k;
      getSpectrum(d, "eta", &eta);
      getSpectrum(d, "k", &k);
      const double alpha = roughness(d, v4, v4 ? 0.0 : 0.01, !v4);
      b = conductorMaterial(eta, k, 1.0f, Spectrum(1.0f), {float(alpha)});
    } else if (type == "mirror") {
      Spectrum kr(0.9f);
      getSpectrum(d, "Kr", &kr);
      // eta 0 + 1i reflects everything; Kr scales it
      b = conductorMaterial(Spectrum(0.0f), Spectrum(1.0f), 1.0f, kr, {});
    } else if (type == "glass" || type == "dielectric") {
      const bool v4 = type == "dielectric";
      PbrtParam* etaParam = d.find(v4 ? "eta" : "index");
      if (!v4 && !etaParam) etaParam = d.find("eta");
      const double eta = scalarIndex(d, etaParam, 1.5);
      if (!(eta > 0) || eta > 100) d.fail("index of refraction must be in (0, 100]");
      if (!v4) {
        Spectrum kr(1.0f), kt(1.0f);
        getSpectrum(d, "Kr", &kr);
        getSpectrum(d, "Kt", &kt);
        auto one = [](const Spectrum& v) { return v.x == 1 && v.y == 1 && v.z == 1; };
        if (!one(kr) || !one(kt)) d.fail("tinted glass (Kr or Kt other than 1) is not supported");
      }
      const double alpha = roughness(d, v4, 0.0);
      if (eta == 1) d.fail("glass of index 1 does not refract; leave the surface out");
      b = dielectricMaterial(float(eta), 1.0f, {float(alpha)});
    } else if (type == "plastic") {
      // pbrt-v3's plastic. pbrt-v3 takes its Fresnel term from inside the coating (index 1.5 to
      // 1, total reflection beyond 42 degrees); the farm takes the physical one, from the air.
      b = readDiffuse(d, "Kd", 0.25f);
      Spectrum ks(0.25f);
      getSpectrum(d, "Ks", &ks);
      const double alpha = roughness(d, false, 0.1, true);
      if (!(alpha > 0)) d.fail("plastic of roughness 0 (without remapping) is not supported");
      b = plasticMaterial(b.reflectance, b.reflectanceTexture, ks, {float(alpha)}, 1.5f, 1.0f);
      warn(d,
           "plastic: its glossy lobe's Fresnel term is a dielectric's seen from the air (pbrt-v3 "
           "computes it from inside the coating, which reflects totally beyond 42 degrees)");
    } else if (type == "coateddiffuse") {
      // pbrt-v4's coateddiffuse, which pbrt evaluates by a random walk between the coat and the
      // base; here in closed form (bsdfs/coated_diffuse.h, with the base's inter-reflections
      // summed as their series, as the walk does).
      const BsdfDescription base = readDiffuse(d, "reflectance", 0.5f);
      const double eta = scalarIndex(d, d.find("eta"), 1.5);
      if (!(eta > 0) || eta > 100 || eta == 1)
        d.fail(what + ": the coat's index of refraction must be in (0, 100] and not 1");
      Spectrum albedo(0.0f);
      getSpectrum(d, "albedo", &albedo);
      if (!isBlack(albedo)) d.fail(what + ": a scattering coat (albedo > 0) is not supported");
      d.getFloat("g", 0);
      d.getInt("maxdepth", 10);  // the random walk's: the series here has no end
      d.getInt("nsamples", 1);
      const double thickness = d.getFloat("thickness", 0.01);
      if (!(thickness >= 0)) d.fail(what + ": thickness must be >= 0");
      const double alpha = roughness(d, true, 0.0);
      b = coatedDiffuseMaterial(base.reflectance, base.reflectanceTexture, Spectrum(1.0f),
                                {float(alpha)}, float(eta), 1.0f, true, d.file, d.line, what);
      warn(d, what +
                  ": rendered in closed form, not by pbrt-v4's random walk; its layer absorbs "
                  "nothing here (pbrt's, of thickness " +
                  formatNumber(thickness) + ", does, slightly)" +
                  (alpha > 0 ? "" : "; its smooth coat is a microfacet coat of roughness 1e-4"));
    } else {
      d.fail(what +
             " is not supported (matte/diffuse, metal/conductor, mirror, glass/dielectric, "
             "plastic, coateddiffuse)");
    }
    // pbrt's BSDFs scatter on both sides of a surface; a dielectric has two sides by nature.
    b.twoSided = b.type != BsdfDescription::Type::Dielectric &&
                 b.type != BsdfDescription::Type::RoughDielectric;
    d.getString("type", "");  // MakeNamedMaterial's, read already
    d.rejectUnused(what);
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

  void parseAreaLight(PbrtDirective& d) {
    if (d.strings[0] != "diffuse")
      d.fail("area light '" + d.strings[0] + "' is not supported (diffuse)");
    Spectrum L(1.0f);
    getSpectrum(d, "L", &L);
    double scale = d.getFloat("scale", 1);
    if (!(scale >= 0)) d.fail("area light scale must be >= 0");
    attrs_.areaLight.twoSided = d.getBool("twosided", false);
    if (d.has("power")) d.fail("area light 'power' is not supported: give L");
    if (d.has("filename")) d.fail("image area lights are not supported");
    d.getInt("nsamples", 1);  // v3's sample count: the farm samples its own way
    d.getInt("samples", 1);
    d.rejectUnused("area light");
    attrs_.areaLight.radiance = L * float(scale);
    attrs_.areaLight.active = true;
  }

  // LightSource "infinite": the environment, constant or a lat-long image (v3's "mapname",
  // v4's "filename"), in the light's coordinate system (z up).
  // A "point3" parameter (v3 also writes "point"), in the light's coordinate system.
  Vec3f getPoint(PbrtDirective& d, const std::string& name, const Vec3f& def) {
    PbrtParam* p = d.typed(name, {"point3", "point"});
    if (!p) return def;
    if (p->numbers.size() != 3) d.failParam(*p, "parameter '" + name + "' takes 3 numbers");
    return Vec3f(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2]));
  }

  // LightSource "point" and "spot": intensity I (times scale) from "from", a spot aimed at "to"
  // with a cone of "coneangle" degrees whose last "conedeltaangle" (v4: "conedelta") fall off.
  void parsePointLight(PbrtDirective& d) {
    const std::string& type = d.strings[0];
    if (inObject_) d.fail("a light source inside an object definition");
    Spectrum I(1.0f), scale(1.0f);
    getSpectrum(d, "I", &I);
    getSpectrum(d, "scale", &scale);
    if (d.has("power")) d.fail(type + " light 'power' is not supported: give I");
    const Vec3f from = getPoint(d, "from", Vec3f(0.0f));
    PointLightDescription light = pointLight(
        attrs_.ctm.applyPoint(from), I * scale,
        fs::path(d.file).filename().string() + ":" + std::to_string(d.line) + " (" + type + ")");
    if (type == "spot") {
      const Vec3f to = getPoint(d, "to", Vec3f(0, 0, 1));
      const double cone = d.getFloat("coneangle", 30);
      double delta = d.getFloat("conedeltaangle", 5);
      if (d.has("conedelta")) delta = d.getFloat("conedelta", 5);
      if (!(cone > 0 && cone <= 180)) d.fail("spot coneangle must be in (0, 180] degrees");
      if (!(delta >= 0 && delta <= cone)) d.fail("spot cone delta must be in [0, coneangle]");
      const Vec3f axis = attrs_.ctm.applyVector(to - from);
      if (!(length(axis) > 0) || !isFinite(axis)) d.fail("spot: \"from\" and \"to\" coincide");
      // v3's falloff; v4's at the end, when the file has shown its version
      aimSpot(&light, axis, cone, cone - delta, PointLightDescription::Falloff::PbrtV3Quartic);
    }
    d.rejectUnused(type + " light");
    if (!isFinite(light.position)) d.fail(type + " light: its position is not finite");
    scene_.pointLights.push_back(light);
  }

  void parseLightSource(PbrtDirective& d) {
    if (d.strings[0] == "point" || d.strings[0] == "spot") return parsePointLight(d);
    if (d.strings[0] != "infinite")
      d.fail("light source '" + d.strings[0] +
             "' is not supported yet (AreaLightSource \"diffuse\"; LightSource "
             "\"infinite\", \"point\" and \"spot\")");
    if (scene_.environment.present) d.fail("more than one infinite light");
    if (inObject_) d.fail("a light source inside an object definition");
    Spectrum L(1.0f), scale(1.0f);
    getSpectrum(d, "L", &L);
    getSpectrum(d, "scale", &scale);
    std::string filename = d.getString("filename", "");
    const std::string mapname = d.getString("mapname", "");
    if (!filename.empty() && !mapname.empty()) d.fail("both \"filename\" and \"mapname\" given");
    // v4's "filename" names a square equal-area map; a lat-long one (v3's "mapname") is taken too.
    const bool equalAreaAllowed = !filename.empty();
    if (filename.empty()) filename = mapname;
    if (d.has("illuminance")) d.fail("infinite light 'illuminance' is not supported");
    if (d.has("portal")) d.fail("infinite light portals are not supported");
    d.getInt("nsamples", 1);  // v3's sample count: the farm samples its own way
    d.getInt("samples", 1);
    d.rejectUnused("infinite light");
    scene_.environment =
        makeEnvironment(dir_, d.file, d.line, L * scale, attrs_.ctm, filename, equalAreaAllowed);
  }

  // ---- Shapes ----

  // ---- Media ----

  int mediumNamed(const PbrtDirective& d, const std::string& name) {
    if (name.empty()) return -1;
    auto it = namedMedia_.find(name);
    if (it == namedMedia_.end()) d.fail("medium '" + name + "' is not defined");
    return it->second;
  }

  // MakeNamedMedium: "homogeneous", or a density grid (pbrt-v3's "heterogeneous", pbrt-v4's
  // "uniformgrid": "density" with x fastest over nx * ny * nz values at cell centres, spanning
  // p0 to p1 in the space of the current transformation; pbrt-v4's "nanovdb" with the grid
  // "density" of an OpenVDB file, a .vdb: NanoVDB's own files are not read). sigma_a and
  // sigma_s are required: pbrt-v3 and v4 default them differently.
  int makeMedium(PbrtDirective& d) {
    const std::string type = d.getString("type", "");
    const std::string what = "medium '" + d.strings[0] + "' of type '" + type + "'";
    if (type != "homogeneous" && type != "heterogeneous" && type != "uniformgrid" &&
        type != "nanovdb")
      d.fail(type.empty() ? "MakeNamedMedium '" + d.strings[0] + "' has no \"string type\""
                          : what +
                                " is not supported (homogeneous, heterogeneous, uniformgrid, "
                                "nanovdb with an OpenVDB file)");
    if (type == "uniformgrid" || type == "nanovdb") sawV4_ = true;
    if (d.has("preset"))
      d.failParam(*d.find("preset"),
                  what +
                      ": named presets (measured coefficients) are not supported: give "
                      "sigma_a and sigma_s");
    for (const char* emission : {"Le", "Lescale", "temperature", "temperaturescale"})
      if (d.has(emission))
        d.failParam(*d.find(emission), what + ": emitting media are not supported");
    MediumDescription m;
    m.id = d.strings[0];
    m.origin = fs::path(d.file).filename().string() + ":" + std::to_string(d.line) + " (" + type +
               " '" + d.strings[0] + "')";
    Spectrum sigmaA, sigmaS;
    if (!getSpectrum(d, "sigma_a", &sigmaA) || !getSpectrum(d, "sigma_s", &sigmaS))
      d.fail(what +
             " needs \"rgb sigma_a\" and \"rgb sigma_s\" (pbrt-v3 and v4 default "
             "them differently)");
    const double scale = d.getFloat("scale", 1);
    if (!(scale >= 0) || !std::isfinite(scale)) d.fail(what + ": scale must be >= 0");
    setScattering(&m, sigmaA, sigmaS, scale);
    m.g = float(d.getFloat("g", 0));
    if (type == "nanovdb") {
      const std::string filename = d.getString("filename", "");
      if (filename.empty()) d.fail(what + " needs a \"string filename\"");
      if (filename.size() < 5 || filename.substr(filename.size() - 4) != ".vdb")
        d.fail(what + ": '" + filename +
               "' is not an OpenVDB file (.vdb); NanoVDB files are not read: convert it "
               "with nanovdb_convert");
      const fs::path file = sceneFilePath(dir_, filename, "volume file", d.file, d.line);
      std::string problem;
      if (!readVdbDensity(file, "density", &m, &problem)) d.fail(filename + ": " + problem);
      const Matrix4 worldToMedium = attrs_.ctm.inverse();
      if (!worldToMedium.isFinite()) d.fail(what + ": the transformation is singular");
      m.worldToGrid = m.worldToGrid * worldToMedium;
    } else if (type != "homogeneous") {
      m.type = MediumDescription::Type::Grid;
      const long long nx = d.getInt("nx", 1), ny = d.getInt("ny", 1), nz = d.getInt("nz", 1);
      if (nx < 1 || ny < 1 || nz < 1 || nx * ny > (1ll << 28) / nz)
        d.fail(what + ": nx, ny and nz must be >= 1 and their product at most 2^28");
      m.nx = int(nx), m.ny = int(ny), m.nz = int(nz);
      const std::vector<double> density = d.getNumbers("density", {"float"}, 1);
      if (density.size() != size_t(nx * ny * nz))
        d.fail(what + ": \"float density\" has " + std::to_string(density.size()) +
               " values for nx * ny * nz = " + std::to_string(nx * ny * nz));
      m.density.assign(density.begin(), density.end());
      const Vec3f p0 = getPoint(d, "p0", Vec3f(0.0f)), p1 = getPoint(d, "p1", Vec3f(1.0f));
      const Matrix4 gridToWorld = attrs_.ctm * Matrix4::translate(p0) * Matrix4::scale(p1 - p0);
      m.worldToGrid = gridToWorld.inverse();
      if (!m.worldToGrid.isFinite()) d.fail(what + ": the box from p0 to p1 is empty");
      m.cellCentred = true;
    }
    d.rejectUnused(what);
    const std::string problem = mediumProblem(m);
    if (!problem.empty()) d.fail(what + ": " + problem);
    scene_.media.push_back(std::move(m));
    return int(scene_.media.size()) - 1;
  }

  void parseShape(PbrtDirective& d) {
    const std::string& type = d.strings[0];
    const std::string what = "shape '" + type + "'";
    for (const char* alpha : {"alpha", "shadowalpha"}) {
      PbrtParam* p = d.find(alpha);
      if (p && (p->type == "texture" || p->numbers.size() != 1 || p->numbers[0] != 1))
        d.failParam(*p, what + ": alpha cut-outs are not supported");
    }
    ShapeDescription shape;
    shape.bsdf = currentMaterial();
    if (attrs_.areaLight.active && !isBlack(attrs_.areaLight.radiance)) {
      shape.isEmitter = true;
      shape.radiance = attrs_.areaLight.radiance;
      shape.emitsBothSides = attrs_.areaLight.twoSided;
    }
    if (shape.bsdf == kInterfaceMaterial) {
      if (shape.isEmitter) d.fail(what + ": an area light on an interface material");
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
      std::vector<double> P = d.getNumbers("P", {"point3"}, 3);
      if (P.empty()) d.fail(what + " has no \"point3 P\"");
      const size_t nv = P.size() / 3;
      std::vector<double> idx = d.getNumbers("indices", {"integer"}, bilinear ? 4 : 3);
      if (idx.empty()) {
        if (nv != (bilinear ? 4u : 3u)) d.fail(what + " has no \"integer indices\"");
        for (size_t k = 0; k < nv; ++k) idx.push_back(double(k));
      }
      std::vector<double> N = d.getNumbers("N", {"normal3"}, 3);
      PbrtParam* uvParam = d.find("uv");
      if (!uvParam) uvParam = d.find("st");
      std::vector<double> uv;
      if (uvParam) {
        if ((uvParam->type != "float" && uvParam->type != "point2") ||
            uvParam->numbers.size() != 2 * nv)
          d.failParam(*uvParam, what + ": uv needs two numbers per vertex");
        uv = uvParam->numbers;
      }
      d.getNumbers("S", {"vector3"}, 3);  // tangents: no anisotropic BSDF reads them
      d.getNumbers("faceIndices", {"integer"}, 1);
      d.rejectUnused(what);
      if (!N.empty() && N.size() != P.size()) d.fail(what + ": N needs one normal per vertex");
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
          d.fail(what + ": index " + formatNumber(v) + " is not one of the " + std::to_string(nv) +
                 " vertices");
      if (bilinear) {
        // Patches p00 p10 p01 p11; a planar one is exactly two triangles.
        for (size_t q = 0; q < idx.size(); q += 4) {
          const Vec3f &p00 = positions[size_t(idx[q])], &p10 = positions[size_t(idx[q + 1])],
                      &p01 = positions[size_t(idx[q + 2])], &p11 = positions[size_t(idx[q + 3])];
          Vec3f n = cross(p10 - p00, p01 - p00);
          float scale = std::max({length(p10 - p00), length(p01 - p00), length(p11 - p00)});
          if (std::fabs(dot(normalize(n), p11 - p00)) > 1e-5f * scale)
            d.fail(what + ": a non-planar bilinear patch is not supported");
          uint32_t a = uint32_t(idx[q]), b = uint32_t(idx[q + 1]), c = uint32_t(idx[q + 2]),
                   e = uint32_t(idx[q + 3]);
          for (uint32_t v : {a, b, e, a, e, c}) shape.indices.push_back(v);
        }
        if (uvs.empty()) {
          // pbrt's default patch parameterization: (0,0) (1,0) (0,1) (1,1) per patch corner;
          // only well defined when patches do not share vertices, so only for textures that
          // need it.
          if (textured) d.fail(what + ": a textured bilinear patch needs uv");
        }
      } else {
        for (double v : idx) shape.indices.push_back(uint32_t(v));
      }
      if (textured && uvs.empty()) {
        // pbrt's default triangle uvs are (0,0) (1,0) (1,1) per triangle: meshes sharing
        // vertices cannot carry them, and a texture read at one point would be a constant.
        d.fail(what + " has a textured material but no uv");
      }
      const bool hasNormals = !normals.empty();
      if (hasNormals && flipWithoutNormals) warnOrientation(d);
      finishMesh(d.file, d.line, what, toWorld, !hasNormals,
                 hasNormals ? false : flipWithoutNormals, std::move(positions), std::move(normals),
                 std::move(uvs), &shape, &scene_.warnings);
      shape.origin += ")";
    } else if (type == "plymesh") {
      std::string filename = d.getString("filename", "");
      if (filename.empty()) d.fail(what + " has no filename");
      if (d.has("displacement")) d.fail(what + ": displacement is not supported");
      d.getFloat("edgelength", 1);
      d.rejectUnused(what);
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
          d.fail("cannot read PLY '" + filename + "': " + e.what());
        }
        plyCache_[path.lexically_normal().string()] = mesh;
      }
      if (textured && mesh.uvs.empty())
        d.fail(what + " '" + filename + "' has a textured material but no texture coordinates");
      shape.indices = std::move(mesh.indices);
      const bool hasNormals = !mesh.normals.empty();
      if (hasNormals && flipWithoutNormals) warnOrientation(d);
      finishMesh(d.file, d.line, "PLY '" + filename + "'", toWorld, !hasNormals,
                 hasNormals ? false : flipWithoutNormals, std::move(mesh.positions),
                 std::move(mesh.normals), std::move(mesh.uvs), &shape, &scene_.warnings);
      shape.origin += " " + filename + ")";
    } else if (type == "sphere") {
      double r = d.getFloat("radius", 1);
      if (!(r > 0)) d.fail("sphere radius must be > 0");
      double zmin = d.getFloat("zmin", -r), zmax = d.getFloat("zmax", r);
      double phimax = d.getFloat("phimax", 360);
      if (zmin > -r || zmax < r || phimax < 360) d.fail("partial spheres are not supported");
      d.rejectUnused(what);
      if (textured) d.fail("textured spheres are not supported");
      double s = similarityScale(d, toWorld);
      shape.type = ShapeDescription::Type::Sphere;
      shape.center = toWorld.applyPoint(Vec3f(0.0f));
      shape.radius = float(r * s);
      shape.flipNormals = flipWithoutNormals;
      if (!(shape.radius > 0) || !std::isfinite(shape.radius) || !isFinite(shape.center))
        d.fail("sphere has a degenerate world-space radius or center");
      shape.origin += ")";
    } else if (type == "disk") {
      double h = d.getFloat("height", 0), r = d.getFloat("radius", 1);
      double inner = d.getFloat("innerradius", 0), phimax = d.getFloat("phimax", 360);
      if (!(r > 0)) d.fail("disk radius must be > 0");
      if (inner != 0 || phimax < 360) d.fail("partial disks (annuli, sectors) are not supported");
      d.rejectUnused(what);
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
      d.fail(what + " is not supported (trianglemesh, plymesh, sphere, disk, bilinearmesh)");
    }
    // A scene-wide budget: a small file can name a large PLY many times, or many disks.
    geometryElements_ += shape.positions.size() + shape.indices.size();
    if (geometryElements_ > kMaxGeometryElements)
      d.fail("the scene's meshes exceed " + std::to_string(kMaxGeometryElements) +
             " vertices and triangle corners in all");
    if (inObject_) {
      // Instanced shapes take no area light (pbrt refuses them too: one light per instance
      // would need the instance's transform in its sampling).
      if (shape.isEmitter) d.fail("an area light inside an object definition is not supported");
      objects_[objectName_].push_back(std::move(shape));
      return;
    }
    scene_.shapes.push_back(std::move(shape));
  }

  // ObjectInstance: the object's shapes (in the space their definition's transformation made)
  // copied through the current transformation, as pbrt's instance-to-world applies it to them.
  void instantiate(PbrtDirective& d) {
    if (inObject_) d.fail("ObjectInstance inside the definition of object '" + objectName_ + "'");
    auto it = objects_.find(d.strings[0]);
    if (it == objects_.end()) d.fail("object '" + d.strings[0] + "' is not defined");
    const Matrix4& m = attrs_.ctm;
    if (std::fabs(determinant3(m)) < 1e-30 || !m.inverse().isFinite())
      d.fail("the instance's transformation is singular");
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
          if (!isFinite(n)) d.fail("the instance's transformation makes a normal non-finite");
        }
        // Without normals the winding tells the outside: a mirror would turn it round.
        if (mirrors)
          for (size_t t = 0; t < shape.indices.size(); t += 3)
            std::swap(shape.indices[t + 1], shape.indices[t + 2]);
        for (const Vec3f& p : shape.positions)
          if (!isFinite(p)) d.fail("the instance's transformation makes a position non-finite");
      }
      geometryElements_ += shape.positions.size() + shape.indices.size();
      if (geometryElements_ > kMaxGeometryElements)
        d.fail("the scene's meshes exceed " + std::to_string(kMaxGeometryElements) +
               " vertices and triangle corners in all");
      scene_.shapes.push_back(std::move(shape));
    }
  }

  // pbrt-v3 turns a mesh with normals round under ReverseOrientation (or a mirror), v4 does not:
  // the farm follows v4 (the normals decide) and says so, as it decides where a light shines.
  void warnOrientation(const PbrtDirective& d) {
    warn(d,
         "mesh with normals under ReverseOrientation or a mirroring transform: oriented by its "
         "normals, as pbrt-v4 does (pbrt-v3 would turn it round)");
  }

  // The uniform scale of a rotation-scale-translation matrix: spheres stay analytic.
  double similarityScale(const PbrtDirective& d, const Matrix4& t) const {
    double s;
    switch (similarityOf(t, &s)) {
      case Similarity::NonUniformScale:
        d.fail("a sphere under a non-uniform scale (an ellipsoid) is not supported");
      case Similarity::Shear:
        d.fail("a sphere under a shear is not supported");
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
  bool sawFilter_ = false, sawV4_ = false;
  std::map<std::string, PlyMesh> plyCache_;
  int defaultMaterial_ = -1;
};

}  // namespace

SceneDescription loadPbrtScene(const std::string& path) {
  return PbrtLoader(path).load();
}

}  // namespace farm
