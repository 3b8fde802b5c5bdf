#pragma once
// Lambertian reflection (Mitsuba's diffuse, pbrt's matte and diffuse), sampled by the cosine.
#include "common/scene/bsdfs/bsdf_model.h"
#include "common/scene/scene_description.h"

namespace farm {

class DiffuseBsdf {
 public:
  static constexpr bool kDelta = false;
  explicit DiffuseBsdf(const BsdfDescription& desc) : reflectance_(desc.reflectance) {}
  Spectrum eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const;
  float pdf(const Vec3f& wo, const Vec3f& wi) const;
  bool sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const;
  bool isBlack() const { return farm::isBlack(reflectance_); }
  void setReflectance(const Spectrum& reflectance) { reflectance_ = reflectance; }

 private:
  Spectrum reflectance_;
};

}  // namespace farm
