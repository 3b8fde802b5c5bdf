#include "common/scene/loaders/material_builders.h"

#include "common/scene/bsdfs/coating_transmittance.h"
#include "common/scene/loaders/scene_files.h"

namespace farm {

const std::vector<MetalIndex>& pbrtNamedMetals() {
  static const std::vector<MetalIndex> metals = {
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
  return metals;
}

const MetalIndex* pbrtNamedMetal(std::string_view name) {
  for (const MetalIndex& m : pbrtNamedMetals())
    if (name == m.name) return &m;
  return nullptr;
}

const MetalIndex& mitsubaCopper() {
  static const MetalIndex copper = {
      "Cu", {0.200438f, 0.924033f, 1.10221f}, {3.91295f, 2.45285f, 2.14219f}};
  return copper;
}

namespace {

// The smooth model, or the rough one and its roughness where alpha > 0 (a smooth one keeps the
// description's defaults, which it does not read).
void setLobe(const Roughness& roughness, BsdfDescription::Type smooth, BsdfDescription::Type rough,
             BsdfDescription* b) {
  if (roughness.alpha > 0) {
    b->type = rough;
    b->distribution = roughness.distribution;
    b->alpha = roughness.alpha;
  } else {
    b->type = smooth;
  }
}

}  // namespace

BsdfDescription diffuseMaterial(const Spectrum& reflectance, int texture) {
  BsdfDescription b;
  b.type = BsdfDescription::Type::Diffuse;
  b.reflectance = reflectance;
  b.reflectanceTexture = texture;
  return b;
}

BsdfDescription conductorMaterial(const Spectrum& eta, const Spectrum& k, float extEta,
                                  const Spectrum& scale, const Roughness& roughness) {
  BsdfDescription b;
  b.eta = eta;
  b.k = k;
  b.extEta = extEta;
  b.specularReflectance = scale;
  setLobe(roughness, BsdfDescription::Type::Conductor, BsdfDescription::Type::RoughConductor, &b);
  return b;
}

BsdfDescription dielectricMaterial(float intIOR, float extIOR, const Roughness& roughness) {
  BsdfDescription b;
  b.intIOR = intIOR;
  b.extIOR = extIOR;
  setLobe(roughness, BsdfDescription::Type::Dielectric, BsdfDescription::Type::RoughDielectric, &b);
  return b;
}

BsdfDescription plasticMaterial(const Spectrum& reflectance, int texture, const Spectrum& specular,
                                const Roughness& roughness, float intIOR, float extIOR) {
  BsdfDescription b = diffuseMaterial(reflectance, texture);
  b.type = BsdfDescription::Type::Plastic;
  b.specularReflectance = specular;
  b.distribution = roughness.distribution;
  b.alpha = roughness.alpha;
  b.intIOR = intIOR;
  b.extIOR = extIOR;
  return b;
}

BsdfDescription coatedDiffuseMaterial(const Spectrum& reflectance, int texture,
                                      const Spectrum& specular, const Roughness& roughness,
                                      float intIOR, float extIOR, bool nonlinear,
                                      const std::string& file, int line, const std::string& what) {
  BsdfDescription b = diffuseMaterial(reflectance, texture);
  b.type = BsdfDescription::Type::CoatedDiffuse;
  b.specularReflectance = specular;
  if (roughness.alpha > 0) {
    b.distribution = roughness.distribution;
    b.alpha = roughness.alpha;
  } else {
    b.distribution = MicrofacetDistribution::GGX;
    b.alpha = kSmoothCoatAlpha;
  }
  b.intIOR = intIOR;
  b.extIOR = extIOR;
  b.nonlinear = nonlinear;
  for (const Spectrum* v : {&b.reflectance, &b.specularReflectance})
    if (v->x > 1 || v->y > 1 || v->z > 1)
      throw SceneLoadError(file, line, what + ": a reflectance above 1 would create energy");
  if (b.intIOR == b.extIOR)
    throw SceneLoadError(file, line,
                         what +
                             ": intIOR and extIOR must differ (the coat's index and the "
                             "outside's)");
  b.coating = sharedCoatingTransmittance(b.distribution, b.alpha, b.intIOR / b.extIOR);
  return b;
}

}  // namespace farm
