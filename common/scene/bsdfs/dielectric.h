#pragma once
// Dielectric interfaces, intIOR on the side the normal leaves, extIOR on the side it points
// into: the smooth one, a Fresnel choice between the mirror and Snell's refraction (Mitsuba's
// dielectric, pbrt's glass and dielectric), and the rough one, microfacet reflection and
// refraction (Mitsuba's roughdielectric, pbrt's rough dielectric; Walter et al. 2007). A
// dielectric has two sides by nature, so neither is two-sided.
#include "common/scene/bsdfs/bsdf_model.h"
#include "common/scene/bsdfs/microfacet.h"
#include "common/scene/scene_description.h"

namespace farm {

class SmoothDielectricBsdf {
 public:
  static constexpr bool kDelta = true;
  explicit SmoothDielectricBsdf(const BsdfDescription& desc)
      : intIOR_(desc.intIOR), extIOR_(desc.extIOR) {}
  Spectrum eval(const Vec3f&, const Vec3f&, TransportMode) const { return Spectrum(0.0f); }
  float pdf(const Vec3f&, const Vec3f&) const { return 0; }
  bool sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const;
  bool isBlack() const { return false; }
  void setReflectance(const Spectrum&) {}

  // Two lobes: the mirror's, chosen with the Fresnel reflectance F, and the refraction's,
  // chosen with 1 - F, where it exists.
  bool specularDirection(const Vec3f& wo, bool reflection, Vec3f* wi) const;
  bool specularLobe(const Vec3f& wo, const Vec3f& wi, TransportMode mode, bool* reflection,
                    float* probability, Spectrum* value) const;
  float diracJacobian(const Vec3f& a, const Vec3f& b) const;
  float intIOR() const { return intIOR_; }
  float extIOR() const { return extIOR_; }

 private:
  float intIOR_, extIOR_;
};

class RoughDielectricBsdf {
 public:
  static constexpr bool kDelta = false;
  explicit RoughDielectricBsdf(const BsdfDescription& desc)
      : facets_{desc.distribution, desc.alpha}, intIOR_(desc.intIOR), extIOR_(desc.extIOR) {}
  Spectrum eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const;
  float pdf(const Vec3f& wo, const Vec3f& wi) const;
  bool sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const;
  bool isBlack() const { return false; }
  void setReflectance(const Spectrum&) {}

 private:
  // The index of refraction on the side the local direction w points into.
  float sideIor(const Vec3f& w) const { return w.z > 0 ? extIOR_ : intIOR_; }
  Microfacet facets_;
  float intIOR_, extIOR_;
};

}  // namespace farm
