#pragma once
// Surface scattering: the BSDF a shading point has, one of the models in bsdfs/ (one class per
// model, each behind the interface bsdfs/bsdf_model.h describes), chosen by the description's
// type. Bsdf is a value (Scene::bsdfAt copies one per shading point of a textured material),
// dispatches to its model, and mirrors the back side of a two-sided one onto its front.
//
// Adding a model: its class in bsdfs/ (a file pair and its tests), a line in Model below and in
// makeModel (bsdf.cpp), its type in BsdfDescription and the loaders' entries for it.
#include <variant>

#include "common/math/vec.h"
#include "common/scene/bsdfs/bsdf_model.h"
#include "common/scene/bsdfs/coated_diffuse.h"
#include "common/scene/bsdfs/conductor.h"
#include "common/scene/bsdfs/dielectric.h"
#include "common/scene/bsdfs/diffuse.h"
#include "common/scene/bsdfs/plastic.h"
#include "common/scene/scene_description.h"

namespace farm {

class Bsdf {
 public:
  // Throws std::invalid_argument for a description no model takes (a two-sided dielectric, a
  // coated diffuse without its coating).
  explicit Bsdf(const BsdfDescription& desc);

  // f(wo, wi) without the cosine; zero for delta lobes.
  Spectrum eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const;
  // Solid-angle density of sample() returning wi given wo; zero for delta lobes.
  float pdf(const Vec3f& wo, const Vec3f& wi) const;
  // u: three uniform numbers (lobe choice, then 2D direction). False when no direction results.
  bool sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const;

  // Has only Dirac lobes (the smooth dielectric and conductor).
  bool isDelta() const;

  // Dirac lobes, for the path-space mutations, which evaluate paths through specular vertices
  // by the coefficients of their delta functions (Veach 1997, 8.3.2).
  // The direction the reflection (or refraction) lobe takes wo to; false where it does not
  // exist (refraction beyond the critical angle) or the BSDF has no Dirac lobes.
  bool specularDirection(const Vec3f& wo, bool reflection, Vec3f* wi) const;
  // The Dirac lobe that joins wo and wi, told by their sides (reflection when on the same side):
  // which lobe, the probability with which sample() chooses it, and its value f |cos wi| / delta
  // for `mode` (the Fresnel term, times the radiance compression of refraction), both from wo.
  // False when there is no such lobe (refraction beyond the critical angle, no Dirac lobes).
  bool specularLobe(const Vec3f& wo, const Vec3f& wi, TransportMode mode, bool* reflection,
                    float* probability, Spectrum* value) const;
  // For directions a and b that a Dirac lobe joins, the ratio of solid angles d(omega_a) /
  // d(omega_b) of the lobe's map from b to a: one for reflection, (eta_b^2 |cos b|) /
  // (eta_a^2 |cos a|) for refraction (etendue is kept: eta^2 cos d(omega) is the same on both
  // sides). It converts a delta function in one direction into one in the other. One for a
  // BSDF without Dirac lobes.
  float diracJacobian(const Vec3f& a, const Vec3f& b) const;
  bool isBlack() const;  // reflects nothing at all (e.g. the black diffuse of a light)
  // The smooth dielectric's indices of refraction inside and outside (the manifold walks and
  // manifold next-event estimation need them, not the lobes); false for every other model.
  bool smoothDielectricIndices(float* intIOR, float* extIOR) const;
  // The texture that gives the diffuse reflectance per shading point (an index into the scene
  // description's textures), or -1; and that reflectance, as the description gave it or as
  // setReflectance (Scene::bsdfAt) last set it.
  int reflectanceTexture() const { return reflectanceTexture_; }
  const Spectrum& reflectance() const { return reflectance_; }
  void setReflectance(const Spectrum& reflectance);

 private:
  using Model =
      std::variant<DiffuseBsdf, SmoothConductorBsdf, RoughConductorBsdf, SmoothDielectricBsdf,
                   RoughDielectricBsdf, PlasticBsdf, CoatedDiffuseBsdf>;
  static Model makeModel(const BsdfDescription& desc);
  // Mitsuba's twosided: the back side behaves as the front.
  bool mirrored(const Vec3f& wo) const { return twoSided_ && wo.z < 0; }

  // What the model does not hold of the description: Scene::bsdfAt copies a Bsdf for every
  // shading point of a textured material, so it keeps these few fields rather than the whole
  // description (a string and a shared coating among them).
  bool twoSided_;
  int reflectanceTexture_;
  Spectrum reflectance_;
  Model model_;
};

}  // namespace farm
