#pragma once
// Surface scattering in the local shading frame (z = normal). Directions point away from the
// surface: wo towards the previous vertex of the path being built, wi the sampled (or connected)
// next one. A small closed set of models, dispatched by type: what the Mitsuba scenes use.
#include "common/math/vec.h"
#include "common/scene/scene_description.h"

namespace farm {

// Which quantity a path carries: the BSDF is not symmetric under refraction (Veach 1997, 5.2).
enum class TransportMode { Radiance, Importance };

struct BsdfSample {
  Vec3f wi;
  Spectrum weight;     // f(wo, wi) |cos(wi)| / pdf
  float pdf = 0;       // solid-angle density (for a delta lobe: the discrete probability)
  bool delta = false;  // sampled from a Dirac lobe: cannot be evaluated or connected to
};

class Bsdf {
 public:
  explicit Bsdf(const BsdfDescription& desc);

  // f(wo, wi) without the cosine; zero for delta lobes.
  Spectrum eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const;
  // Solid-angle density of sample() returning wi given wo; zero for delta lobes.
  float pdf(const Vec3f& wo, const Vec3f& wi) const;
  // u: three uniform numbers (lobe choice, then 2D direction). False when no direction results.
  bool sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const;

  bool isDelta() const { return type_ == BsdfDescription::Type::Dielectric; }
  bool isBlack() const;  // reflects nothing at all (e.g. the black diffuse of a light)
  const BsdfDescription& description() const { return desc_; }

 private:
  BsdfDescription desc_;
  BsdfDescription::Type type_;
};

// Fresnel reflectance of a dielectric interface for cos(theta_i) (sign: which side) and the
// relative index eta = n_inside / n_outside; sets *cosThetaT to the refracted cosine (>= 0).
float fresnelDielectric(float cosThetaI, float eta, float* cosThetaT);
// Fresnel reflectance of a conductor with complex index eta + i k (relative to the exterior).
Spectrum fresnelConductor(float cosThetaI, const Spectrum& eta, const Spectrum& k);

}  // namespace farm
