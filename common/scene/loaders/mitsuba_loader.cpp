#include "common/scene/loaders/mitsuba_loader.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <pugixml.hpp>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "common/scene/loaders/camera_builders.h"
#include "common/scene/loaders/grid_volume_reader.h"
#include "common/scene/loaders/light_builders.h"
#include "common/scene/loaders/material_builders.h"
#include "common/scene/loaders/medium_builders.h"
#include "common/scene/loaders/mitsuba_document.h"
#include "common/scene/loaders/mitsuba_properties.h"
#include "common/scene/loaders/ply_reader.h"
#include "common/scene/loaders/scene_files.h"
#include "common/scene/loaders/serialized_reader.h"
#include "common/scene/loaders/vdb_reader.h"
#include "common/scene/medium.h"
#include "common/scene/mesh_cleanup.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr double kPiDouble = 3.14159265358979323846;

class MitsubaLoader {
 public:
  explicit MitsubaLoader(const std::string& path) : doc_(path) {}

  SceneDescription load() {
    scene_.sourcePath = doc_.path();
    pugi::xml_node root = doc_.root();
    scene_.strictNormals = false;  // Mitsuba's default, without an integrator that says otherwise
    bool sawSensor = false, sawIntegrator = false;
    for (pugi::xml_node child : root.children()) {
      if (child.type() != pugi::node_element) continue;
      std::string_view tag = child.name();
      if (tag == "integrator") {
        if (sawIntegrator) doc_.fail(child, "more than one <integrator>");
        sawIntegrator = true;
        parseIntegrator(child);
      } else if (tag == "sensor") {
        if (sawSensor) doc_.fail(child, "more than one <sensor>; the farm renders one camera");
        sawSensor = true;
        parseSensor(child);
      } else if (tag == "bsdf") {
        int index = addBsdf(parseBsdf(child));
        doc_.registerId(child, "bsdf", index);
      } else if (tag == "shape") {
        parseShape(child);
      } else if (tag == "emitter") {
        parseTopLevelEmitter(child);
      } else if (tag == "texture") {
        doc_.registerId(child, "texture", parseTexture(child));
      } else if (tag == "medium") {
        doc_.registerId(child, "medium", parseMedium(child));
      } else {
        doc_.failUnknownElement(child);
      }
    }
    return std::move(scene_);
  }

 private:
  // ---- Errors and line numbers ----

  // ---- File and XML ----

  // ---- Properties ----

  // ---- Objects ----

  void parseIntegrator(const pugi::xml_node& node) {
    // Only the path length and the shading-normal convention matter to the farm: it picks its own
    // algorithms (see the render plan).
    std::vector<pugi::xml_node> nested;
    MitsubaProperties props(doc_, node, &nested);
    // Mitsuba's Monte Carlo integrators default strictNormals to false (set before the scene is
    // read); the file's value holds, from whichever integrator, wrapping or wrapped, says it.
    scene_.strictNormals = props.getBoolean("strictNormals", scene_.strictNormals);
    if (pugi::xml_node n = props.take("maxDepth")) {
      long long depth = doc_.integer(n, "maxDepth");
      if (depth < -1 || depth > 1000000) doc_.fail(n, "maxDepth must be -1 (unbounded) or >= 0");
      scene_.maxDepth = int(depth);
      return;
    }
    // Wrapping integrators (adaptive, irrcache, ...) hold the real one inside.
    for (const pugi::xml_node& child : nested)
      if (std::string_view(child.name()) == "integrator") parseIntegrator(child);
  }

  void parseSensor(const pugi::xml_node& node) {
    std::string type = node.attribute("type").as_string();
    if (type != "perspective" && type != "thinlens")
      doc_.fail(node, "unknown or unsupported sensor type '" + type +
                          "' (perspective and thinlens only)");
    doc_.registerId(node, "sensor", 0);
    std::vector<pugi::xml_node> nested;
    MitsubaProperties props(doc_, node, &nested);
    CameraDescription& cam = scene_.camera;
    if (pugi::xml_node t = props.take("toWorld")) cam.toWorld = doc_.transformOf(t);

    // The film first: Mitsuba resolves "smaller"/"larger" against the film's aspect ratio.
    bool sawFilm = false, sawCameraMedium = false;
    for (const pugi::xml_node& child : nested) {
      std::string_view tag = child.name();
      if (tag == "film") {
        if (sawFilm) doc_.fail(child, "more than one <film>");
        sawFilm = true;
        parseFilm(child);
      } else if (tag == "sampler") {
        // The farm chooses its own sampling.
      } else if (tag == "medium" || tag == "ref") {
        // The medium the camera sits in (Mitsuba's sensor medium).
        if (sawCameraMedium) doc_.fail(child, "a sensor takes one medium");
        sawCameraMedium = true;
        cam.medium = tag == "ref" ? doc_.resolveRef(child, "medium") : parseMedium(child);
      } else {
        doc_.failUnknownElement(child);
      }
    }

    pugi::xml_node fovNode = props.take("fov");
    pugi::xml_node focalNode = props.take("focalLength");
    if (fovNode && focalNode) doc_.fail(focalNode, "give either fov or focalLength, not both");
    pugi::xml_node axisNode;
    std::string axis = toLower(props.getString("fovAxis", "x", &axisNode));
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
      doc_.fail(axisNode, "fovAxis '" + axis + "' is not one of x, y, smaller, larger, diagonal");
    }
    double fov;
    if (fovNode) {
      doc_.requireTag(fovNode, {"float", "integer"});
      fov = doc_.number(fovNode, doc_.requireValue(fovNode), "parameter 'fov'");
      if (!(fov > 0 && fov < 180)) doc_.fail(fovNode, "fov must be in (0, 180) degrees");
    } else {
      // Mitsuba: a 35 mm film equivalent focal length ("50mm" by default) sets the diagonal fov.
      double focal = 50;
      if (focalNode) {
        doc_.requireTag(focalNode, {"string", "float", "integer"});
        std::string f(trim(doc_.requireValue(focalNode)));
        if (f.size() > 2 && toLower(f.substr(f.size() - 2)) == "mm") f.resize(f.size() - 2);
        focal = doc_.number(focalNode, f, "parameter 'focalLength'");
        if (!(focal > 0)) doc_.fail(focalNode, "focalLength must be positive");
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
        if (!n)
          doc_.fail(node, std::string("a thinlens sensor needs <float name=\"") + name + "\">");
        doc_.requireTag(n, {"float", "integer"});
        double v = doc_.number(n, doc_.requireValue(n), std::string("parameter '") + name + "'");
        if (!(v > 0)) doc_.fail(n, std::string(name) + " must be > 0");
        (name[0] == 'a' ? cam.lensRadius : cam.focusDistance) = float(v);
      }
    }
    // Clip planes, shutter times and focus distance do not change a pinhole render.
  }

  void parseFilm(const pugi::xml_node& node) {
    std::vector<pugi::xml_node> nested;
    MitsubaProperties props(doc_, node, &nested);
    CameraDescription& cam = scene_.camera;
    long long width = cam.width, height = cam.height;
    pugi::xml_node widthNode = props.take("width"), heightNode = props.take("height");
    if (widthNode) width = doc_.integer(widthNode, "width");
    if (heightNode) height = doc_.integer(heightNode, "height");
    if (width < 1 || width > kMaxFilmSide)
      doc_.fail(widthNode ? widthNode : node,
                "film width " + std::to_string(width) + " is not in [1, 65536]");
    if (height < 1 || height > kMaxFilmSide)
      doc_.fail(heightNode ? heightNode : node,
                "film height " + std::to_string(height) + " is not in [1, 65536]");
    if (width * height > kMaxFilmPixels)
      doc_.fail(node, "film of " + std::to_string(width) + "x" + std::to_string(height) +
                          " pixels exceeds 2^28 pixels");
    cam.width = int(width);
    cam.height = int(height);
    // Other film parameters (file format, gamma, banner, crop) are about Mitsuba's output.
    bool sawFilter = false;
    for (const pugi::xml_node& child : nested) {
      if (std::string_view(child.name()) != "rfilter") doc_.failUnknownElement(child);
      if (sawFilter) doc_.fail(child, "more than one <rfilter>");
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
        MitsubaProperties filterProps(doc_, child, &filterNested);
        for (const pugi::xml_node& n : filterNested) doc_.failUnknownElement(n);
        double stddev = 0.5;
        if (pugi::xml_node n = filterProps.take("stddev")) {
          doc_.requireTag(n, {"float", "integer"});
          stddev = doc_.number(n, doc_.requireValue(n), "parameter 'stddev'");
          // Its radius 4 stddev must reach half a pixel, so that every film point reaches a
          // pixel centre.
          if (!(stddev >= 0.125 && stddev <= 4))
            doc_.fail(n, "stddev must be in [0.125, 4] pixels");
        }
        filterProps.rejectUnused("rfilter type 'gaussian'");
        setGaussianFilter(&cam, 4 * stddev, 1 / (2 * stddev * stddev));
      } else {
        doc_.fail(child, "unknown or unsupported reconstruction filter type '" + type +
                             "' (supported: tent, box, gaussian)");
      }
    }
  }

  // intIOR and extIOR of a (rough) dielectric.
  std::pair<float, float> parseDielectricIndex(MitsubaProperties& props, const std::string& type) {
    const float intIOR = float(props.getIor("intIOR", 1.5046));
    const float extIOR = float(props.getIor("extIOR", 1.000277));
    // The description has no slot for tinted glass: accept only Mitsuba's default of 1.
    for (const char* name : {"specularReflectance", "specularTransmittance"}) {
      pugi::xml_node n = props.take(name);
      if (n &&
          !(doc_.spectrumOf(n).x == 1 && doc_.spectrumOf(n).y == 1 && doc_.spectrumOf(n).z == 1))
        doc_.fail(n, std::string(name) + " other than 1 is not supported for " + type);
    }
    return {intIOR, extIOR};
  }

  // The microfacet distribution and its roughness, of roughconductor, roughdielectric and
  // roughplastic.
  Roughness parseRoughness(const pugi::xml_node& node, MitsubaProperties& props) {
    Roughness r;
    pugi::xml_node distNode;
    std::string dist = toLower(props.getString("distribution", "beckmann", &distNode));
    if (dist == "beckmann") {
      r.distribution = MicrofacetDistribution::Beckmann;
    } else if (dist == "ggx") {
      r.distribution = MicrofacetDistribution::GGX;
    } else {
      doc_.fail(distNode, "unsupported microfacet distribution '" + dist + "' (beckmann or ggx)");
    }
    pugi::xml_node alphaNode = props.take("alpha");
    pugi::xml_node alphaU = props.take("alphaU"), alphaV = props.take("alphaV");
    double alpha = 0.1;
    if (alphaNode && (alphaU || alphaV)) doc_.fail(alphaNode, "give either alpha or alphaU/alphaV");
    auto readAlpha = [&](const pugi::xml_node& n) {
      doc_.requireTag(n, {"float", "integer"});
      return doc_.number(n, doc_.requireValue(n),
                         "parameter '" + std::string(n.attribute("name").value()) + "'");
    };
    if (alphaNode) {
      alpha = readAlpha(alphaNode);
    } else if (alphaU || alphaV) {
      if (!alphaU || !alphaV) doc_.fail(alphaU ? alphaU : alphaV, "alphaU and alphaV go together");
      double u = readAlpha(alphaU), v = readAlpha(alphaV);
      if (u != v) doc_.fail(alphaU, "anisotropic roughness (alphaU != alphaV) is not supported");
      alpha = u;
    }
    if (!(alpha > 0))
      doc_.fail(alphaNode ? alphaNode : (alphaU ? alphaU : node), "alpha must be > 0");
    // Below 1e-4 the microfacet distributions lose precision; such a surface is a mirror anyway.
    r.alpha = float(std::max(alpha, 1e-4));
    props.take("sampleVisible");  // a sampling choice, not a look
    return r;
  }

  // Mitsuba's plastic and roughplastic: a diffuse base under a dielectric coat
  // (coatedDiffuseMaterial), of the diffuse `texture` if >= 0.
  BsdfDescription parseCoatedDiffuse(const pugi::xml_node& node, MitsubaProperties& props,
                                     const std::string& type, int texture) {
    Roughness roughness;  // smooth: coatedDiffuseMaterial's coat of kSmoothCoatAlpha
    if (type == "roughplastic") {
      roughness = parseRoughness(node, props);
    } else {
      scene_.warnings.push_back(
          doc_.origin(node) +
          ": plastic: its smooth coat is rendered as a microfacet coat of roughness 1e-4 (the same "
          "image, except that point lights leave a tiny highlight)");
    }
    const float intIOR = float(props.getIor("intIOR", 1.49));  // polypropylene
    const float extIOR = float(props.getIor("extIOR", 1.000277));
    const bool nonlinear = props.getBoolean("nonlinear", false);
    const Spectrum specular = props.getSpectrum("specularReflectance", Spectrum(1.0f));
    const Spectrum reflectance = props.getSpectrum("diffuseReflectance", Spectrum(0.5f));
    return coatedDiffuseMaterial(reflectance, texture, specular, roughness, intIOR, extIOR,
                                 nonlinear, doc_.path(), doc_.lineOf(node), type);
  }

  // A (rough) conductor: its complex index of refraction and its reflectance scale.
  BsdfDescription parseConductor(MitsubaProperties& props, const Roughness& roughness) {
    pugi::xml_node materialNode;
    std::string material = props.getString("material", "Cu", &materialNode);
    Spectrum eta, k;
    if (material == "Cu") {
      eta = mitsubaCopper().eta;
      k = mitsubaCopper().k;
    } else if (toLower(material) == "none") {
      eta = Spectrum(0.0f);
      k = Spectrum(1.0f);
    } else {
      doc_.fail(materialNode, "conductor material '" + material +
                                  "' is not supported; give eta and k as <rgb> (or Cu, none)");
    }
    eta = props.getSpectrum("eta", eta);
    k = props.getSpectrum("k", k);
    const float extEta = float(props.getIor("extEta", 1.0));
    const Spectrum scale = props.getSpectrum("specularReflectance", Spectrum(1.0f));
    return conductorMaterial(eta, k, extEta, scale, roughness);
  }

  BsdfDescription parseBsdf(const pugi::xml_node& node) {
    std::string type = node.attribute("type").as_string();
    std::vector<pugi::xml_node> nested;
    MitsubaProperties props(doc_, node, &nested);
    BsdfDescription b;
    std::string what = "bsdf type '" + type + "'";
    if (type == "twosided") {
      if (nested.size() != 1)
        doc_.fail(node, nested.empty()
                            ? "twosided needs one nested <bsdf>"
                            : "twosided with more than one nested <bsdf> (different sides) "
                              "is not supported");
      const pugi::xml_node& inner = nested[0];
      std::string_view tag = inner.name();
      if (tag == "bsdf") {
        b = parseBsdf(inner);
      } else if (tag == "ref") {
        b = scene_.bsdfs[doc_.resolveRef(inner, "bsdf")];
      } else {
        doc_.failUnknownElement(inner);
      }
      if (b.type == BsdfDescription::Type::Dielectric ||
          b.type == BsdfDescription::Type::RoughDielectric) {
        // A dielectric's two sides differ by nature (the relative index flips): mirroring the
        // back onto the front would swap reflection and transmission with the wrong index.
        doc_.fail(node,
                  "twosided cannot wrap a dielectric: a dielectric already has two sides "
                  "(Mitsuba refuses this too)");
      }
      b.twoSided = true;
      b.id = node.attribute("id").as_string();
      props.rejectUnused(what);
      return b;
    }
    // Textured parameters: <texture name="reflectance" ...> or <ref name="reflectance" id=.../>.
    // Only a diffuse reflectance may be textured.
    int texture = -1;
    const char* texturable = type == "diffuse"                               ? "reflectance"
                             : (type == "plastic" || type == "roughplastic") ? "diffuseReflectance"
                                                                             : nullptr;
    for (const pugi::xml_node& child : nested) {
      std::string_view tag = child.name();
      if (tag != "texture" && !(tag == "ref" && child.attribute("name")))
        doc_.failUnknownElement(child);
      const std::string name = child.attribute("name").as_string();
      if (name.empty()) doc_.fail(child, "a <" + std::string(tag) + "> in a bsdf needs a name");
      if (!texturable || name != texturable)
        doc_.fail(child,
                  "a textured '" + name + "' is not supported for " + what +
                      (texturable ? std::string(" (only its ") + texturable + " may be)" : ""));
      if (props.has(name.c_str()) || texture >= 0)
        doc_.fail(child, "parameter '" + name + "' given twice");
      texture = tag == "ref" ? doc_.resolveRef(child, "texture") : parseTexture(child);
    }
    if (type == "diffuse") {
      b = diffuseMaterial(props.getSpectrum("reflectance", Spectrum(0.5f)), texture);
    } else if (type == "dielectric") {
      const auto [intIOR, extIOR] = parseDielectricIndex(props, "dielectric");
      b = dielectricMaterial(intIOR, extIOR, {});
    } else if (type == "conductor") {
      b = parseConductor(props, {});
    } else if (type == "roughconductor") {
      const Roughness roughness = parseRoughness(node, props);
      b = parseConductor(props, roughness);
    } else if (type == "roughdielectric") {
      const Roughness roughness = parseRoughness(node, props);
      const auto [intIOR, extIOR] = parseDielectricIndex(props, "roughdielectric");
      // Equal indices refract nothing: every refraction goes straight through, where the
      // microfacet transmission lobe is singular (its Jacobian's denominator vanishes).
      if (intIOR == extIOR)
        doc_.fail(
            node,
            "roughdielectric with intIOR equal to extIOR does not refract; leave the surface out");
      b = dielectricMaterial(intIOR, extIOR, roughness);
    } else if (type == "plastic" || type == "roughplastic") {
      b = parseCoatedDiffuse(node, props, type, texture);
    } else {
      doc_.fail(node,
                "unknown or unsupported bsdf type '" + type +
                    "' (supported: diffuse, twosided, dielectric, roughdielectric, conductor, "
                    "roughconductor, plastic, roughplastic)");
    }
    b.id = node.attribute("id").as_string();
    props.rejectUnused(what);
    return b;
  }

  // <texture type="bitmap">: an image looked up bilinearly at the surface's (u, v), scaled and
  // offset. Mitsuba's row v = 0 is the image's top; the description's (t = 0 at the bottom row)
  // gets there because every Mitsuba shape's texture coordinates enter it as (u, 1 - v) (see
  // mitsubaUv), and this mapping is written for those: t = vscale v' + (1 - vscale - voffset).
  int parseTexture(const pugi::xml_node& node) {
    std::string type = node.attribute("type").as_string();
    if (type != "bitmap") doc_.fail(node, "unsupported texture type '" + type + "' (bitmap only)");
    std::vector<pugi::xml_node> nested;
    MitsubaProperties props(doc_, node, &nested);
    for (const pugi::xml_node& child : nested) doc_.failUnknownElement(child);
    pugi::xml_node fileNode;
    const std::string filename = props.getString("filename", "", &fileNode);
    if (trim(filename).empty())
      doc_.fail(fileNode ? fileNode : node, "bitmap texture has no filename");
    TextureDescription t;
    t.type = TextureDescription::Type::Image;
    const std::string wrap = props.getString("wrapMode", "repeat");
    const std::string wrapU = props.getString("wrapModeU", wrap);
    const std::string wrapV = props.getString("wrapModeV", wrap);
    if (wrapU != wrapV) doc_.fail(node, "different wrap modes in u and v are not supported");
    if (wrapU == "repeat") {
      t.wrap = TextureWrap::Repeat;
    } else if (wrapU == "clamp") {
      t.wrap = TextureWrap::Clamp;
    } else if (wrapU == "zero" || wrapU == "black") {
      t.wrap = TextureWrap::Black;
    } else {
      doc_.fail(node, "texture wrap mode '" + wrapU + "' is not supported (repeat, clamp, zero)");
    }
    TextureEncoding encoding = TextureEncoding::Automatic;
    if (pugi::xml_node g = props.take("gamma")) {
      doc_.requireTag(g, {"float", "integer"});
      const double gamma = doc_.number(g, doc_.requireValue(g), "parameter 'gamma'");
      if (gamma == -1) {
        encoding = TextureEncoding::SRGB;
      } else if (gamma == 1) {
        encoding = TextureEncoding::Linear;
      } else if (gamma != 0) {
        doc_.fail(g, "texture gamma " + std::string(doc_.requireValue(g)) +
                         " is not supported (-1 for sRGB, 1 for linear, or leave it out)");
      }
    }
    if (props.has("channel"))
      doc_.fail(props.take("channel"), "single-channel textures are not supported");
    // EWA and trilinear filtering average the texture over a pixel's footprint; here the pixel
    // filter and the samples do that.
    const std::string filter = props.getString("filterType", "ewa");
    if (filter != "ewa" && filter != "trilinear" && filter != "nearest")
      doc_.fail(node, "unknown texture filterType '" + filter + "' (ewa, trilinear, nearest)");
    props.getNumber("maxAnisotropy", 20);
    props.getBoolean("cache", false);
    const double uvScale = props.getNumber("uvscale", 1);
    const double uScale = props.getNumber("uscale", uvScale);
    const double vScale = props.getNumber("vscale", uvScale);
    const double uOffset = props.getNumber("uoffset", 0);
    const double vOffset = props.getNumber("voffset", 0);
    props.rejectUnused("texture type 'bitmap'");
    t.uScale = float(uScale);
    t.uOffset = float(uOffset);
    t.vScale = float(vScale);
    t.vOffset = float(1 - vScale - vOffset);
    t.image = images_.load(doc_.dir(), filename, encoding, doc_.path(), doc_.lineOf(fileNode));
    t.origin = doc_.origin(node) + " (bitmap " + filename + ")";
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
      doc_.fail(node, "unsupported emitter type '" + type + "' inside a shape (only area)");
    MitsubaProperties props(doc_, node, nullptr);
    Spectrum radiance = props.getSpectrum("radiance", Spectrum(1.0f));
    props.take("samplingWeight");  // light selection is the farm's own business
    props.rejectUnused("emitter type 'area'");
    return radiance;
  }

  // <emitter type="point"> and <emitter type="spot">: intensity from a position (point's
  // "position", or toWorld's origin); a spot looks down its toWorld's +z, fully bright within
  // beamWidth and dark beyond cutoffAngle (degrees).
  void parsePointEmitter(const pugi::xml_node& node, const std::string& type) {
    MitsubaProperties props(doc_, node, nullptr);
    props.take("samplingWeight");
    const Spectrum intensity = props.getSpectrum("intensity", Spectrum(1.0f));
    Matrix4 toWorld = Matrix4::identity();
    if (pugi::xml_node t = props.take("toWorld")) toWorld = doc_.transformOf(t);
    PointLightDescription light =
        pointLight(toWorld.applyPoint(props.getPoint("position", Vec3f(0.0f))), intensity,
                   doc_.origin(node) + " (" + type + ")");
    if (type == "spot") {
      const double cutoff = props.getNumber("cutoffAngle", 20);
      const double beam = props.getNumber("beamWidth", cutoff * 3 / 4);
      if (!(cutoff > 0 && cutoff <= 90))
        doc_.fail(node, "spot cutoffAngle must be in (0, 90] degrees");
      if (!(beam >= 0 && beam <= cutoff))
        doc_.fail(node, "spot beamWidth must be in [0, cutoffAngle]");
      const Vec3f axis = toWorld.applyVector(Vec3f(0, 0, 1));
      if (!(length(axis) > 0) || !isFinite(axis)) doc_.fail(node, "spot toWorld is singular");
      aimSpot(&light, axis, cutoff, beam, PointLightDescription::Falloff::MitsubaLinearAngle);
    }
    props.rejectUnused("emitter type '" + type + "'");
    if (!isFinite(light.position)) doc_.fail(node, type + " emitter: its position is not finite");
    scene_.pointLights.push_back(light);
  }

  // <emitter> at the top level: the environment (constant, envmap) or a point light.
  void parseTopLevelEmitter(const pugi::xml_node& node) {
    std::string type = node.attribute("type").as_string();
    if (type == "area")
      doc_.fail(node, "an area <emitter> must be nested in the <shape> that emits");
    if (type == "point" || type == "spot") return parsePointEmitter(node, type);
    if (type != "constant" && type != "envmap")
      doc_.fail(node, "unsupported emitter type '" + type +
                          "' (area emitters nested in shapes, constant, envmap, point and spot)");
    if (scene_.environment.present)
      doc_.fail(node, "more than one environment emitter (constant or envmap)");
    MitsubaProperties props(doc_, node, nullptr);
    props.take("samplingWeight");  // light selection is the farm's own business
    Spectrum scale(1.0f);
    std::string filename;
    Matrix4 toWorld = Matrix4::identity();
    if (type == "constant") {
      scale = props.getSpectrum("radiance", Spectrum(1.0f));
    } else {
      pugi::xml_node where;
      filename = props.getString("filename", "", &where);
      if (filename.empty()) doc_.fail(node, "envmap has no filename");
      scale = props.getSpectrum("scale", Spectrum(1.0f));
      if (pugi::xml_node t = props.take("toWorld")) toWorld = doc_.transformOf(t);
      props.take("cache");  // Mitsuba's MIP map cache: nothing to cache here
    }
    props.rejectUnused("emitter type '" + type + "'");
    // Mitsuba's lat-long frame has y up and u = atan2(x, -z) / 2 pi; the description's is
    // pbrt's (z up, u = atan2(y, x) / 2 pi): local Mitsuba (x, y, z) = (y', z', -x') of pbrt's.
    Matrix4 mitsubaFromPbrt;
    mitsubaFromPbrt.m[0] = {0, 1, 0, 0};
    mitsubaFromPbrt.m[1] = {0, 0, 1, 0};
    mitsubaFromPbrt.m[2] = {-1, 0, 0, 0};
    mitsubaFromPbrt.m[3] = {0, 0, 0, 1};
    scene_.environment = makeEnvironment(doc_.dir(), doc_.path(), doc_.lineOf(node), scale,
                                         toWorld * mitsubaFromPbrt, filename, false);
  }

  // <medium type="homogeneous">: sigmaA and sigmaS, or sigmaT and albedo, times scale.
  // <medium type="heterogeneous">: sigma_t = scale times a density volume (a gridvolume file or
  // a constvolume), a constant albedo. Either with a <phase> (isotropic or hg). Returns its
  // index in scene_.media.
  int parseMedium(const pugi::xml_node& node) {
    doc_.checkAttributes(node, {"type", "id", "name"});
    const std::string type = node.attribute("type").as_string();
    if (type != "homogeneous" && type != "heterogeneous")
      doc_.fail(node, "unknown or unsupported medium type '" + type +
                          "' (homogeneous and heterogeneous only)");
    std::vector<pugi::xml_node> nested;
    MitsubaProperties props(doc_, node, &nested);
    MediumDescription m;
    m.id = node.attribute("id").as_string();
    m.origin = doc_.origin(node) + " (" + type + ")";
    if (pugi::xml_node n = props.take("material"))
      doc_.fail(n,
                "named medium materials (measured coefficients) are not supported: give sigmaA "
                "and sigmaS");
    const double scale = props.getNumber("scale", props.getNumber("densityMultiplier", 1.0));
    if (!(scale >= 0) || !std::isfinite(scale)) doc_.fail(node, "a medium's scale must be >= 0");
    bool sawPhase = false;
    pugi::xml_node densityNode, albedoNode;
    for (const pugi::xml_node& child : nested) {
      const std::string_view tag = child.name();
      if (tag == "phase") {
        if (sawPhase) doc_.fail(child, "a medium takes one phase function");
        sawPhase = true;
        m.g = parsePhase(child);
      } else if (tag == "volume" && type == "heterogeneous") {
        const std::string name = child.attribute("name").as_string();
        if (name != "density" && name != "albedo")
          doc_.fail(child, "a heterogeneous medium's volumes are 'density' and 'albedo', not '" +
                               name + "'");
        (name == "density" ? densityNode : albedoNode) = child;
      } else {
        doc_.failUnknownElement(child);
      }
    }
    if (type == "homogeneous") {
      const bool coefficients = props.has("sigmaA") || props.has("sigmaS");
      const bool extinction = props.has("sigmaT") || props.has("albedo");
      if (coefficients && extinction)
        doc_.fail(node, "give sigmaA and sigmaS, or sigmaT and albedo, not both");
      if (extinction) {
        const Spectrum sigmaT = props.getSpectrum("sigmaT", Spectrum(1.0f));
        const Spectrum albedo = props.getSpectrum("albedo", Spectrum(1.0f));
        setExtinction(&m, sigmaT, albedo, scale);
      } else {
        const Spectrum sigmaA = props.getSpectrum("sigmaA", Spectrum(1.0f));
        const Spectrum sigmaS = props.getSpectrum("sigmaS", Spectrum(1.0f));
        setScattering(&m, sigmaA, sigmaS, scale);
      }
    } else {
      props.take("method");    // Woodcock tracking is what the farm does anyway
      props.take("stepSize");  // ray marching's step: the farm's estimators need none
      if (!densityNode) doc_.fail(node, "a heterogeneous medium needs a <volume name=\"density\">");
      Spectrum albedo(1.0f);
      if (albedoNode) albedo = constantVolume(albedoNode, "albedo");
      const float constant = parseDensityVolume(densityNode, &m);
      // Mitsuba: sigma_t = scale * density, sigma_s = sigma_t * albedo.
      setExtinction(&m, Spectrum(float(scale * constant)), albedo, 1.0);
    }
    props.rejectUnused("medium type '" + type + "'");
    const std::string problem = mediumProblem(m);
    if (!problem.empty()) doc_.fail(node, problem);
    scene_.media.push_back(std::move(m));
    return int(scene_.media.size()) - 1;
  }

  // <phase type="isotropic"/> or <phase type="hg"><float name="g" .../></phase>: the g of a
  // Henyey-Greenstein phase function (0: isotropic).
  double parsePhase(const pugi::xml_node& node) {
    const std::string type = node.attribute("type").as_string();
    MitsubaProperties props(doc_, node, nullptr);
    double g = 0;
    if (type == "hg") {
      g = props.getNumber("g", 0.8);
      if (!(std::fabs(g) < 1)) doc_.fail(node, "the Henyey-Greenstein g must lie in (-1, 1)");
    } else if (type != "isotropic") {
      doc_.fail(node,
                "unknown or unsupported phase function '" + type + "' (isotropic and hg only)");
    }
    props.rejectUnused("phase function '" + type + "'");
    return g;
  }

  // A constvolume's value (the albedo; a grid of albedos is not supported).
  Spectrum constantVolume(const pugi::xml_node& node, const std::string& what) {
    const std::string type = node.attribute("type").as_string();
    if (type != "constvolume")
      doc_.fail(node, "the " + what + " volume must be a constvolume (not '" + type + "')");
    MitsubaProperties props(doc_, node, nullptr);
    const Spectrum v = props.getSpectrum("value", Spectrum(1.0f));
    props.rejectUnused("volume type 'constvolume'");
    return v;
  }

  // The density: a constvolume (the same everywhere: *m becomes homogeneous, and the value is
  // returned as a factor of sigma_t) or a gridvolume file, whose samples span its bounding box
  // corner to corner, placed in the world by its toWorld (returns 1).
  float parseDensityVolume(const pugi::xml_node& node, MediumDescription* m) {
    const std::string type = node.attribute("type").as_string();
    if (type == "constvolume") {
      const Spectrum v = constantVolume(node, "density");
      if (v.x != v.y || v.x != v.z) doc_.fail(node, "a density must be a single number");
      m->type = MediumDescription::Type::Homogeneous;
      return v.x;
    }
    m->type = MediumDescription::Type::Grid;
    if (type != "gridvolume")
      doc_.fail(node,
                "unknown or unsupported volume type '" + type + "' (gridvolume, constvolume)");
    MitsubaProperties props(doc_, node, nullptr);
    pugi::xml_node fileNode;
    const std::string filename = props.getString("filename", "", &fileNode);
    if (!fileNode || trim(filename).empty()) doc_.fail(node, "a gridvolume needs a filename");
    Matrix4 toWorld = Matrix4::identity();
    if (pugi::xml_node t = props.take("toWorld")) toWorld = doc_.transformOf(t);
    props.take("sendData");  // a network-rendering switch
    // The farm's extension: an OpenVDB file's float grid (gridName, or the first one).
    const bool vdb = filename.size() > 4 && toLower(filename.substr(filename.size() - 4)) == ".vdb";
    pugi::xml_node gridNameNode;
    const std::string gridName = vdb ? props.getString("gridName", "", &gridNameNode) : "";
    props.rejectUnused("volume type 'gridvolume'");
    const Matrix4 worldToVolume = toWorld.inverse();
    if (!worldToVolume.isFinite()) doc_.fail(node, "the gridvolume's toWorld is singular");
    const std::filesystem::path file =
        sceneFilePath(doc_.dir(), filename, "volume file", doc_.path(), doc_.lineOf(fileNode));
    std::string problem;
    if (vdb) {
      if (!readVdbDensity(file, gridName, m, &problem))
        doc_.fail(fileNode, filename + ": " + problem);
      m->worldToGrid = m->worldToGrid * worldToVolume;
      return 1;
    }
    const std::string bytes =
        readSceneFile(file, "volume file", doc_.path(), doc_.lineOf(fileNode));
    GridVolume volume;
    if (!decodeGridVolume(bytes, &volume, &problem)) doc_.fail(fileNode, filename + ": " + problem);
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
      doc_.fail(node, "unknown or unsupported shape type '" + type +
                          "' (supported: rectangle, cube, sphere, obj, ply, serialized)");
    std::vector<pugi::xml_node> nested;
    MitsubaProperties props(doc_, node, &nested);
    ShapeDescription shape;
    std::string origin = doc_.origin(node) + " (" + type;

    // Material and emission first: they need no geometry.
    int bsdf = -1;
    pugi::xml_node emitterNode;
    for (const pugi::xml_node& child : nested) {
      std::string_view tag = child.name();
      const std::string_view name = child.attribute("name").value();
      if ((tag == "medium" || tag == "ref") && (name == "interior" || name == "exterior")) {
        // The media on either side: <medium name="interior" ...> or <ref name="interior" .../>.
        int& side = name == "interior" ? shape.interiorMedium : shape.exteriorMedium;
        if (side >= 0) doc_.fail(child, "shape has more than one " + std::string(name) + " medium");
        side = tag == "ref" ? doc_.resolveRef(child, "medium") : parseMedium(child);
        shape.hasMediumInterface = true;
      } else if (tag == "bsdf" || tag == "ref") {
        if (bsdf >= 0) doc_.fail(child, "shape has more than one bsdf");
        if (tag == "ref") {
          bsdf = doc_.resolveRef(child, "bsdf");
        } else {
          bsdf = addBsdf(parseBsdf(child));
          doc_.registerId(child, "bsdf", bsdf);
        }
      } else if (tag == "emitter") {
        if (emitterNode) doc_.fail(child, "shape has more than one emitter");
        emitterNode = child;
        shape.radiance = parseAreaEmitter(child);
        // A black emitter emits nothing: treat it as a plain surface, so that no light sampling
        // ever has to pick a light of zero power.
        shape.isEmitter = !isBlack(shape.radiance);
      } else {
        doc_.failUnknownElement(child);
      }
    }
    if (bsdf < 0 && shape.hasMediumInterface) {
      // Mitsuba's medium transition: a shape with media and no BSDF only bounds them.
      if (shape.isEmitter)
        doc_.fail(node,
                  "an emitting shape that bounds a medium needs a BSDF (its surface scatters)");
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
      doc_.fail(node, "a textured " + type +
                          " is not supported (texture coordinates come from meshes "
                          "and rectangles only)");

    Matrix4 toWorld = Matrix4::identity();
    pugi::xml_node transformNode = props.take("toWorld");
    if (transformNode) toWorld = doc_.transformOf(transformNode);
    bool flip = props.getBoolean("flipNormals", false);
    std::string what = "shape type '" + type + "'";

    if (type == "sphere") {
      shape.type = ShapeDescription::Type::Sphere;
      Vec3f center = props.getPoint("center", Vec3f(0.0f));
      pugi::xml_node radiusNode = props.take("radius");
      double radius = 1.0;
      if (radiusNode) {
        doc_.requireTag(radiusNode, {"float", "integer"});
        radius = doc_.number(radiusNode, doc_.requireValue(radiusNode), "parameter 'radius'");
        if (!(radius > 0)) doc_.fail(radiusNode, "sphere radius must be > 0");
      }
      shape.center = toWorld.applyPoint(center);
      shape.radius = float(radius * similarityScale(transformNode ? transformNode : node, toWorld));
      if (!(shape.radius > 0) || !std::isfinite(shape.radius) || !isFinite(shape.center))
        doc_.fail(node, "sphere has a degenerate world-space radius or center");
      shape.flipNormals = flip;
      props.rejectUnused(what);
      shape.origin = origin + ")";
      scene_.shapes.push_back(std::move(shape));
      doc_.registerId(node, "shape", int(scene_.shapes.size()) - 1);
      return;
    }

    shape.type = ShapeDescription::Type::TriangleMesh;
    // A mirroring transform turns counter-clockwise triangles clockwise; generated shapes keep
    // their outward orientation by reversing the winding then.
    bool mirrored = determinant3(toWorld) < 0;
    if (type == "rectangle") {
      props.rejectUnused(what);
      makeRectangle(toWorld, mirrored != flip, flip, &shape);
      shape.origin = origin + ")";
    } else if (type == "cube") {
      props.rejectUnused(what);
      makeCube(toWorld, mirrored != flip, &shape);
      shape.origin = origin + ")";
    } else {
      pugi::xml_node fileNode;
      std::string filename = props.getString("filename", "", &fileNode);
      if (!fileNode) doc_.fail(node, type + " shape without a filename parameter");
      if (trim(filename).empty()) doc_.fail(fileNode, "empty " + type + " filename");
      bool faceNormals = props.getBoolean("faceNormals", false);
      bool flipTexCoords = true;
      long long shapeIndex = 0;
      if (type == "obj") {
        flipTexCoords = props.getBoolean("flipTexCoords", true);
        props.getBoolean("collapse", false);  // we always merge an OBJ's groups into one mesh
      } else if (type == "ply") {
        props.getBoolean("srgb", true);  // vertex colours: no texture reads them
      } else if (pugi::xml_node n = props.take("shapeIndex")) {
        shapeIndex = doc_.integer(n, "shapeIndex");
        if (shapeIndex < 0 || shapeIndex > std::numeric_limits<int>::max())
          doc_.fail(n, "shapeIndex must be >= 0");
      }
      if (pugi::xml_node n = props.take("maxSmoothAngle"))
        doc_.fail(n, "maxSmoothAngle (normals rebuilt at creases) is not supported");
      props.rejectUnused(what);
      if (type == "obj") {
        loadObj(fileNode, filename, toWorld, faceNormals, flip, flipTexCoords, &shape);
      } else if (type == "ply") {
        loadPly(fileNode, filename, toWorld, faceNormals, flip, &shape);
      } else {
        loadSerialized(fileNode, filename, int(shapeIndex), toWorld, faceNormals, flip, &shape);
      }
      if (textured && shape.uvs.empty())
        doc_.fail(fileNode,
                  type + " '" + filename + "' has a textured material but no texture coordinates");
      shape.origin = origin + " " + filename + ")";
    }
    scene_.shapes.push_back(std::move(shape));
    doc_.registerId(node, "shape", int(scene_.shapes.size()) - 1);
  }

  // The uniform scale factor of a rotation-scale-translation matrix; spheres stay analytic, so an
  // ellipsoid-making transform is refused.
  double similarityScale(const pugi::xml_node& node, const Matrix4& t) const {
    double s;
    switch (similarityOf(t, &s)) {
      case Similarity::NonUniformScale:
        doc_.fail(node,
                  "sphere toWorld has a non-uniform scale (the sphere would be an ellipsoid)");
      case Similarity::Shear:
        doc_.fail(node, "sphere toWorld has a shear");
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
    const fs::path objPath =
        sceneFilePath(doc_.dir(), filename, "mesh file", doc_.path(), doc_.lineOf(fileNode));

    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    // From memory, with no material library: tinyobj would open whatever file an `mtllib` line
    // names (outside the scene's folder, or /dev/zero), and materials come from the XML anyway.
    tinyobj::ObjReader reader;
    if (!reader.ParseFromString(
            readSceneFile(objPath, "OBJ '" + filename + "'", doc_.path(), doc_.lineOf(fileNode)),
            "", config)) {
      std::string err = reader.Error();
      while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
      doc_.fail(fileNode,
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
    if (corners.empty()) doc_.fail(fileNode, "OBJ '" + filename + "' contains no triangles");
    bool fileNormals = !faceNormals && numNormals > 0;
    bool fileTexcoords = numTexcoords > 0;
    for (const tinyobj::index_t& c : corners) {
      if (c.vertex_index < 0 || size_t(c.vertex_index) >= numPositions)
        doc_.fail(fileNode, "OBJ '" + filename + "' has a face with an invalid vertex index");
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
    finishMesh(doc_.path(), doc_.lineOf(fileNode), "OBJ '" + filename + "'", toWorld, faceNormals,
               flip, std::move(positions), std::move(normals), std::move(uvs), shape,
               &scene_.warnings);
  }

  // A PLY mesh through Open Asset Import Library (ply_reader.h).
  void loadPly(const pugi::xml_node& fileNode, const std::string& filename, const Matrix4& toWorld,
               bool faceNormals, bool flip, ShapeDescription* shape) {
    const std::string bytes = readSceneFile(
        sceneFilePath(doc_.dir(), filename, "mesh file", doc_.path(), doc_.lineOf(fileNode)),
        "PLY '" + filename + "'", doc_.path(), doc_.lineOf(fileNode));
    PlyMesh mesh;
    try {
      mesh = parsePly(bytes);
    } catch (const std::exception& e) {
      doc_.fail(fileNode, "cannot read PLY '" + filename + "': " + e.what());
    }
    shape->indices = std::move(mesh.indices);
    for (Vec2f& uv : mesh.uvs) uv = mitsubaUv(uv);
    finishMesh(doc_.path(), doc_.lineOf(fileNode), "PLY '" + filename + "'", toWorld, faceNormals,
               flip, std::move(mesh.positions), std::move(mesh.normals), std::move(mesh.uvs), shape,
               &scene_.warnings);
  }

  // One mesh of a Mitsuba serialized file (serialized_reader.h); the file's face-normal flag
  // acts as faceNormals does.
  void loadSerialized(const pugi::xml_node& fileNode, const std::string& filename, int shapeIndex,
                      const Matrix4& toWorld, bool faceNormals, bool flip,
                      ShapeDescription* shape) {
    const std::string bytes = readSceneFile(
        sceneFilePath(doc_.dir(), filename, "mesh file", doc_.path(), doc_.lineOf(fileNode)),
        "serialized mesh '" + filename + "'", doc_.path(), doc_.lineOf(fileNode));
    SerializedMesh mesh;
    try {
      mesh = parseSerialized(bytes, shapeIndex, kMaxMeshElements);
    } catch (const std::exception& e) {
      doc_.fail(fileNode, "cannot read serialized mesh '" + filename + "': " + e.what());
    }
    shape->indices = std::move(mesh.indices);
    for (Vec2f& uv : mesh.uvs) uv = mitsubaUv(uv);
    finishMesh(doc_.path(), doc_.lineOf(fileNode), "serialized mesh '" + filename + "'", toWorld,
               faceNormals || mesh.faceNormals, flip, std::move(mesh.positions),
               std::move(mesh.normals), std::move(mesh.uvs), shape, &scene_.warnings);
  }

  static constexpr size_t kMaxMeshElements = size_t(1) << 28;  // vertices + triangle corners

  MitsubaDocument doc_;
  SceneDescription scene_;
  TextureImageCache images_;
};

}  // namespace

SceneDescription loadMitsubaScene(const std::string& path) {
  return MitsubaLoader(path).load();
}

}  // namespace farm
