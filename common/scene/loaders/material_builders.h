#pragma once
// The scattering models a scene file may name, each made here from physical values, so that the
// two loaders only read their own names and spell their own errors. What each format's names mean,
// side by side (a loader's parameters in brackets; bsdfs/ holds each model's evaluation):
//
// | model (BsdfDescription::Type) | Mitsuba 0.6 | pbrt-v3 | pbrt-v4 |
// |---|---|---|---|
// | Diffuse | diffuse (reflectance) | matte (Kd; sigma 0) | diffuse (reflectance) |
// | Conductor, RoughConductor | conductor, roughconductor (material, eta, k, extEta,
// specularReflectance; alpha, distribution) | metal (eta, k; roughness through pbrt-v3's remap),
// mirror (Kr) | conductor (eta, k; roughness, its square root) | | Dielectric, RoughDielectric |
// dielectric, roughdielectric (intIOR, extIOR; alpha, distribution) | glass (index or eta; Kr and
// Kt of 1) | dielectric (eta; roughness) | | Plastic | (none) | plastic (Kd, Ks, roughness) |
// (none) | | CoatedDiffuse | plastic, roughplastic (diffuseReflectance, specularReflectance,
// intIOR, extIOR, nonlinear; alpha, distribution) | (none) | coateddiffuse (reflectance, eta,
// roughness) |
//
// Every pbrt surface scatters on both sides (twoSided) but glass; a Mitsuba one where the file
// wraps it in "twosided". pbrt's microfacets are Trowbridge-Reitz (GGX); Mitsuba's Beckmann
// unless the file says ggx.
#include <string>
#include <string_view>
#include <vector>

#include "common/scene/scene_description.h"

namespace farm {

// A complex index of refraction (eta + i k) as RGB.
struct MetalIndex {
  const char* name;
  Spectrum eta, k;
};

// pbrt-v4's named metal spectra ("metal-Au-eta"): the spectral data integrated to linear sRGB
// (the table Tungsten ships; CuZn, absent there, is the brass of Mitsuba's documentation).
const std::vector<MetalIndex>& pbrtNamedMetals();
// The one of pbrtNamedMetals() called `name` ("Cu"), or nullptr.
const MetalIndex* pbrtNamedMetal(std::string_view name);

// Copper, Mitsuba's default conductor (the values its exporter writes for "Cu").
const MetalIndex& mitsubaCopper();

// A microfacet lobe's roughness; alpha 0: a smooth surface (a Dirac lobe).
struct Roughness {
  float alpha = 0;
  MicrofacetDistribution distribution = MicrofacetDistribution::GGX;
};

// The alpha of a coat a file calls smooth: CoatedDiffuse has no Dirac coat, and one of this
// roughness renders as the smooth one does except that point lights leave a tiny highlight.
constexpr float kSmoothCoatAlpha = 1e-4f;

// A Lambertian reflectance, or where texture >= 0 SceneDescription::textures[texture].
BsdfDescription diffuseMaterial(const Spectrum& reflectance, int texture);

// A conductor of index `index` under a medium of index extEta, its Fresnel reflectance scaled by
// `scale` (Mitsuba's specularReflectance, pbrt's mirror Kr); rough where roughness.alpha > 0.
BsdfDescription conductorMaterial(const Spectrum& eta, const Spectrum& k, float extEta,
                                  const Spectrum& scale, const Roughness& roughness);

// The boundary between an interior of index intIOR and an exterior of extIOR; rough where
// roughness.alpha > 0.
BsdfDescription dielectricMaterial(float intIOR, float extIOR, const Roughness& roughness);

// pbrt-v3's plastic: a diffuse lobe plus a glossy one (roughness.alpha > 0) of reflectance
// `specular` with the Fresnel term of a dielectric of index intIOR seen from extIOR.
BsdfDescription plasticMaterial(const Spectrum& reflectance, int texture, const Spectrum& specular,
                                const Roughness& roughness, float intIOR, float extIOR);

// A dielectric coat of index intIOR (over extIOR) on a Lambertian base (bsdfs/coated_diffuse.h);
// a smooth coat (alpha 0) is one of kSmoothCoatAlpha and GGX. Reflectances above 1 and equal
// indices are SceneLoadErrors at file:line naming `what`; the coat's transmittance table is shared
// with identical coats.
BsdfDescription coatedDiffuseMaterial(const Spectrum& reflectance, int texture,
                                      const Spectrum& specular, const Roughness& roughness,
                                      float intIOR, float extIOR, bool nonlinear,
                                      const std::string& file, int line, const std::string& what);

}  // namespace farm
