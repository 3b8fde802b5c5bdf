#pragma once
// The microfacet theory every rough model shares (Walter et al. 2007, "Microfacet models for
// refraction through rough surfaces"): a distribution of facet normals, Smith's shadowing, the
// sampling of a facet and its density, and the half vectors that recover the facet a pair of
// directions reflects or refracts through. Local shading frame, z = the macro normal.
#include "common/math/vec.h"
#include "common/scene/scene_description.h"

namespace farm {

struct Microfacet {
  MicrofacetDistribution distribution;
  float alpha;  // roughness: the distribution's width

  // D(m): facet normals' density per unit projected area (eqs. 25 and 33).
  float D(const Vec3f& m) const;
  // Smith's monodirectional shadowing G1(v, m) (eq. 27 with the rational fit, and eq. 34).
  float G1(const Vec3f& v, const Vec3f& m) const;
  // The facet normal a BSDF samples for wo (of either side): GGX normals visible from wo
  // (Heitz 2018), Beckmann normals by D(m) cos(theta_m). Always m.z > 0.
  Vec3f sample(const Vec3f& wo, float u1, float u2) const;
  // The density of sample()'s m (facing wo).
  float pdf(const Vec3f& wo, const Vec3f& m) const;
  // What is left of f |cos(theta_i)| / pdf for a facet m sampled by sample(), once D, the
  // Fresnel term (and, for refraction, the eta factors and Jacobians) cancel: G1(wo, m) G1(wi, m)
  // |wo.m| / (|wo.z| m.z) for Beckmann (eq. 41), and G1(wi, m) for visible GGX normals. In
  // closed form from m, so it stays exact where recomputing the half vector from float
  // directions would not (tiny alpha at grazing angles).
  float weight(const Vec3f& wo, const Vec3f& wi, const Vec3f& m) const;
};

// The half vector of a reflection (eq. 13), oriented to +z; false when wo and wi are opposite
// and there is none.
bool reflectionHalfVector(const Vec3f& wo, const Vec3f& wi, Vec3f* h);

// A refraction's half vector (eq. 16), from eta_o on wo's side and eta_i on wi's: the
// generalized half vector, oriented to +z; zero where there is none.
Vec3f transmissionHalfVector(const Vec3f& wo, const Vec3f& wi, float etaO, float etaI);

}  // namespace farm
