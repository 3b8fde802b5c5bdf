#pragma once
// pbrt-v3's plastic: the sum of a Lambertian lobe and a Torrance-Sparrow lobe whose Fresnel
// term is a dielectric's; nothing couples them (Kd + Ks <= 1 keeps it energy-conserving). Both
// lobes are sampled, each in proportion to its reflectance's luminance.
#include "common/scene/bsdfs/bsdf_model.h"
#include "common/scene/bsdfs/glossy_lobe.h"
#include "common/scene/scene_description.h"

namespace farm {

class PlasticBsdf {
 public:
  static constexpr bool kDelta = false;
  explicit PlasticBsdf(const BsdfDescription& desc)
      : reflectance_(desc.reflectance), glossy_(desc) {}
  Spectrum eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const;
  float pdf(const Vec3f& wo, const Vec3f& wi) const;
  bool sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const;
  bool isBlack() const;
  void setReflectance(const Spectrum& reflectance) { reflectance_ = reflectance; }

 private:
  float diffuseProbability() const;
  Spectrum reflectance_;
  GlossyLobe glossy_;
};

}  // namespace farm
