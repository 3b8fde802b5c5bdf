#include "common/scene/bsdfs/diffuse.h"

#include "common/sampling/warp.h"

namespace farm {

Spectrum DiffuseBsdf::eval(const Vec3f& wo, const Vec3f& wi, TransportMode) const {
  if (wo.z <= 0 || wi.z <= 0) return Spectrum(0.0f);
  return reflectance_ * kInvPi;
}

float DiffuseBsdf::pdf(const Vec3f& wo, const Vec3f& wi) const {
  if (wo.z <= 0 || wi.z <= 0) return 0;
  return cosineHemispherePdf(wi.z);
}

bool DiffuseBsdf::sample(const Vec3f& wo, const float u[3], TransportMode, BsdfSample* out) const {
  if (wo.z <= 0) return false;
  Vec3f wi = squareToCosineHemisphere({u[1], u[2]});
  if (wi.z <= 0) return false;
  out->wi = wi;
  out->pdf = cosineHemispherePdf(wi.z);
  out->weight = reflectance_;
  out->delta = false;
  return true;
}

}  // namespace farm
