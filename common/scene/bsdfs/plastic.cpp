#include "common/scene/bsdfs/plastic.h"

namespace farm {

Spectrum PlasticBsdf::eval(const Vec3f& wo, const Vec3f& wi, TransportMode) const {
  if (wo.z <= 0 || wi.z <= 0) return Spectrum(0.0f);
  return reflectance_ * kInvPi + glossy_.eval(wo, wi);
}

float PlasticBsdf::pdf(const Vec3f& wo, const Vec3f& wi) const {
  return diffuseOrGlossyPdf(diffuseProbability(), glossy_, wo, wi);
}

bool PlasticBsdf::sample(const Vec3f& wo, const float u[3], TransportMode mode,
                         BsdfSample* out) const {
  return sampleDiffuseOrGlossy(*this, diffuseProbability(), glossy_, wo, u, mode, out);
}

bool PlasticBsdf::isBlack() const {
  return farm::isBlack(reflectance_) && farm::isBlack(glossy_.specularReflectance());
}

float PlasticBsdf::diffuseProbability() const {
  const float d = luminance(reflectance_), g = luminance(glossy_.specularReflectance());
  return d + g > 0 ? d / (d + g) : 0.5f;
}

}  // namespace farm
