#include "common/scene/bsdfs/glossy_lobe.h"

#include "common/scene/bsdfs/fresnel.h"

namespace farm {

Spectrum GlossyLobe::eval(const Vec3f& wo, const Vec3f& wi) const {
  Vec3f h;
  if (wo.z <= 0 || wi.z <= 0 || !reflectionHalfVector(wo, wi, &h)) return Spectrum(0.0f);
  const float d = facets_.D(h);
  if (d == 0) return Spectrum(0.0f);
  const float g = facets_.G1(wo, h) * facets_.G1(wi, h);
  float cosT;
  const float f = fresnelDielectric(dot(wo, h), eta_, &cosT);
  return specularReflectance_ * (f * d * g / (4 * wo.z * wi.z));
}

bool GlossyLobe::sample(const Vec3f& wo, float u1, float u2, Vec3f* wi) const {
  const Vec3f m = facets_.sample(wo, u1, u2);
  if (dot(wo, m) <= 0) return false;
  *wi = reflect(wo, m);
  return true;
}

float diffuseOrGlossyPdf(float diffuseProbability, const GlossyLobe& glossy, const Vec3f& wo,
                         const Vec3f& wi) {
  if (wo.z <= 0 || wi.z <= 0) return 0;
  float pdf = diffuseProbability * cosineHemispherePdf(wi.z);
  Vec3f h;
  if (reflectionHalfVector(wo, wi, &h))  // the facet's density, the reflection Jacobian (eq. 14)
    pdf += (1 - diffuseProbability) * glossy.facets().pdf(wo, h) / (4 * absDot(wo, h));
  return pdf;
}

}  // namespace farm
