#pragma once
// A Lambertian base under a rough dielectric coat (Mitsuba's roughplastic and plastic,
// pbrt-v4's coateddiffuse; Weidlich and Wilkie 2007 for the smooth case): the coat's glossy
// reflection (GlossyLobe) plus the base seen through it, whose light the coat's rough
// transmittance (CoatingTransmittance) lets in and out.
#include <memory>

#include "common/scene/bsdfs/bsdf_model.h"
#include "common/scene/bsdfs/coating_transmittance.h"
#include "common/scene/bsdfs/glossy_lobe.h"
#include "common/scene/scene_description.h"

namespace farm {

class CoatedDiffuseBsdf {
 public:
  static constexpr bool kDelta = false;
  // The description must carry its coating, which this model then shares. A copy is a view: it
  // points at the coating without sharing it, so it must not outlive the model it was copied
  // from (Scene::bsdfAt copies one per shading point, from Bsdfs the Scene keeps; a shared
  // count changed by every thread at once would be a contended cache line). Moves move the
  // share.
  explicit CoatedDiffuseBsdf(const BsdfDescription& desc);
  CoatedDiffuseBsdf(const CoatedDiffuseBsdf& other);
  CoatedDiffuseBsdf& operator=(const CoatedDiffuseBsdf& other);
  CoatedDiffuseBsdf(CoatedDiffuseBsdf&&) noexcept = default;
  CoatedDiffuseBsdf& operator=(CoatedDiffuseBsdf&&) noexcept = default;
  ~CoatedDiffuseBsdf() = default;

  Spectrum eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const;
  float pdf(const Vec3f& wo, const Vec3f& wi) const;
  bool sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const;
  bool isBlack() const;
  void setReflectance(const Spectrum& reflectance) { reflectance_ = reflectance; }

 private:
  Spectrum base(const Vec3f& wo, const Vec3f& wi) const;
  float glossyProbability(const Vec3f& wo) const;  // that sample() takes the glossy lobe
  Spectrum reflectance_;
  GlossyLobe glossy_;
  float eta_;       // the coat's index over the outside's
  bool nonlinear_;  // Mitsuba's "nonlinear" (scene_description.h)
  const CoatingTransmittance* coating_ = nullptr;
  std::shared_ptr<const CoatingTransmittance> coatingShare_;  // empty in copies
};

}  // namespace farm
