#include "common/scene/bsdfs/conductor.h"

#include <cmath>

#include "common/scene/bsdfs/fresnel.h"

namespace farm {

ConductorFresnel::ConductorFresnel(const BsdfDescription& desc)
    : specularReflectance_(desc.specularReflectance),
      eta_(desc.eta / desc.extEta),
      k_(desc.k / desc.extEta) {}

Spectrum ConductorFresnel::operator()(float cosThetaI) const {
  return specularReflectance_ * fresnelConductor(cosThetaI, eta_, k_);
}

bool SmoothConductorBsdf::sample(const Vec3f& wo, const float*, TransportMode,
                                 BsdfSample* out) const {
  if (wo.z <= 0) return false;
  out->wi = Vec3f(-wo.x, -wo.y, wo.z);
  out->pdf = 1;
  out->weight = fresnel_(wo.z);
  out->delta = true;
  return !farm::isBlack(out->weight);  // as specularLobe(): no lobe carries nothing
}

bool SmoothConductorBsdf::specularDirection(const Vec3f& wo, bool reflection, Vec3f* wi) const {
  if (!reflection || !(wo.z > 0)) return false;
  *wi = Vec3f(-wo.x, -wo.y, wo.z);
  return true;
}

bool SmoothConductorBsdf::specularLobe(const Vec3f& wo, const Vec3f& wi, TransportMode,
                                       bool* reflection, float* probability,
                                       Spectrum* value) const {
  if (!(wo.z * wi.z > 0) || !(wo.z > 0)) return false;
  *reflection = true;
  *probability = 1;
  *value = fresnel_(std::fabs(wo.z));
  return !farm::isBlack(*value);
}

Spectrum RoughConductorBsdf::eval(const Vec3f& wo, const Vec3f& wi, TransportMode) const {
  Vec3f h;
  if (wo.z <= 0 || wi.z <= 0 || !reflectionHalfVector(wo, wi, &h)) return Spectrum(0.0f);
  float d = facets_.D(h);
  if (d == 0) return Spectrum(0.0f);
  float g = facets_.G1(wo, h) * facets_.G1(wi, h);
  return fresnel_(dot(wo, h)) * (d * g / (4 * wo.z * wi.z));
}

float RoughConductorBsdf::pdf(const Vec3f& wo, const Vec3f& wi) const {
  Vec3f h;
  if (wo.z <= 0 || wi.z <= 0 || !reflectionHalfVector(wo, wi, &h)) return 0;
  // the facet's density; the reflection Jacobian is 1 / (4 |wo.m|) (eq. 14)
  return facets_.pdf(wo, h) / (4 * absDot(wo, h));
}

bool RoughConductorBsdf::sample(const Vec3f& wo, const float u[3], TransportMode,
                                BsdfSample* out) const {
  if (wo.z <= 0) return false;
  const Vec3f m = facets_.sample(wo, u[1], u[2]);
  const float womDot = dot(wo, m);
  if (womDot <= 0) return false;
  const Vec3f wi = reflect(wo, m);
  if (wi.z <= 0) return false;
  const float pdf = facets_.pdf(wo, m) / (4 * womDot);
  if (!(pdf > 0)) return false;
  out->wi = wi;
  out->pdf = pdf;
  // f cos / pdf in closed form from m: D cancels (Microfacet::weight).
  out->weight = fresnel_(womDot) * facets_.weight(wo, wi, m);
  out->delta = false;
  return isValidRadiance(out->weight);
}

}  // namespace farm
