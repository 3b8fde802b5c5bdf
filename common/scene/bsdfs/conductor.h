#pragma once
// Conductors: the smooth one, a Fresnel mirror (Mitsuba's conductor, pbrt's mirror and metal
// or conductor of roughness 0), and the rough one, Torrance-Sparrow reflection with a
// conductor's Fresnel term (Mitsuba's roughconductor, pbrt's rough metal; Walter et al. 2007,
// eq. 20).
#include "common/scene/bsdfs/bsdf_model.h"
#include "common/scene/bsdfs/microfacet.h"
#include "common/scene/scene_description.h"

namespace farm {

// The Fresnel reflectance of a conductor of complex index eta + i k in an exterior of index
// extEta, times a specular reflectance (Mitsuba's scale on it).
class ConductorFresnel {
 public:
  explicit ConductorFresnel(const BsdfDescription& desc);
  Spectrum operator()(float cosThetaI) const;
  bool isBlack() const { return farm::isBlack(specularReflectance_); }

 private:
  Spectrum specularReflectance_, eta_, k_;  // eta and k relative to the exterior
};

class SmoothConductorBsdf {
 public:
  static constexpr bool kDelta = true;
  explicit SmoothConductorBsdf(const BsdfDescription& desc) : fresnel_(desc) {}
  Spectrum eval(const Vec3f&, const Vec3f&, TransportMode) const { return Spectrum(0.0f); }
  float pdf(const Vec3f&, const Vec3f&) const { return 0; }
  bool sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const;
  bool isBlack() const { return fresnel_.isBlack(); }
  void setReflectance(const Spectrum&) {}

  // One lobe, the mirror's, chosen always; its value is the Fresnel reflectance.
  bool specularDirection(const Vec3f& wo, bool reflection, Vec3f* wi) const;
  bool specularLobe(const Vec3f& wo, const Vec3f& wi, TransportMode mode, bool* reflection,
                    float* probability, Spectrum* value) const;
  float diracJacobian(const Vec3f&, const Vec3f&) const { return 1; }  // reflection keeps it

 private:
  ConductorFresnel fresnel_;
};

class RoughConductorBsdf {
 public:
  static constexpr bool kDelta = false;
  explicit RoughConductorBsdf(const BsdfDescription& desc)
      : fresnel_(desc), facets_{desc.distribution, desc.alpha} {}
  Spectrum eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const;
  float pdf(const Vec3f& wo, const Vec3f& wi) const;
  bool sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const;
  bool isBlack() const { return fresnel_.isBlack(); }
  void setReflectance(const Spectrum&) {}

 private:
  ConductorFresnel fresnel_;
  Microfacet facets_;
};

}  // namespace farm
