#include "common/scene/bsdfs/dielectric.h"

#include <cmath>

#include "common/scene/bsdfs/fresnel.h"

namespace farm {

bool SmoothDielectricBsdf::sample(const Vec3f& wo, const float u[3], TransportMode mode,
                                  BsdfSample* out) const {
  float eta = intIOR_ / extIOR_;
  float cosI = wo.z, cosT;
  float fr = fresnelDielectric(cosI, eta, &cosT);
  out->delta = true;
  if (u[0] < fr) {
    out->wi = Vec3f(-wo.x, -wo.y, wo.z);
    out->pdf = fr;
    out->weight = Spectrum(1.0f);
    return true;
  }
  float etaTI = cosI > 0 ? eta : 1 / eta;  // index ratio transmitted side / incident side
  out->wi = refracted(wo, etaTI, cosT);
  out->pdf = 1 - fr;
  // Radiance is compressed by (eta_i / eta_t)^2 when it crosses into the denser medium; the
  // adjoint (importance) is not (Veach 1997, eq. 5.15).
  float scale = mode == TransportMode::Radiance ? 1 / (etaTI * etaTI) : 1.0f;
  out->weight = Spectrum(scale);
  return true;
}

bool SmoothDielectricBsdf::specularDirection(const Vec3f& wo, bool reflection, Vec3f* wi) const {
  if (wo.z == 0) return false;
  if (reflection) {
    *wi = Vec3f(-wo.x, -wo.y, wo.z);
    return true;
  }
  float eta = intIOR_ / extIOR_, cosT;
  if (fresnelDielectric(wo.z, eta, &cosT) >= 1) return false;  // total internal reflection
  *wi = refracted(wo, wo.z > 0 ? eta : 1 / eta, cosT);
  return true;
}

bool SmoothDielectricBsdf::specularLobe(const Vec3f& wo, const Vec3f& wi, TransportMode mode,
                                        bool* reflection, float* probability,
                                        Spectrum* value) const {
  if (wo.z == 0) return false;
  const float eta = intIOR_ / extIOR_;
  float cosT;
  const float fr = fresnelDielectric(wo.z, eta, &cosT);
  // Which lobe joins the two is told by their sides alone, not by how closely wi follows the
  // lobe: paths recompute directions from float vertex positions, and rays start a little off
  // the surface (Scene::spawnRay), which turns an edge of half a millimetre (a ray across the
  // corner of a glass block) by a tenth of a radian. Paths only ever meet a specular vertex
  // through its lobes, so nothing else needs telling apart.
  if (wo.z * wi.z > 0) {
    *reflection = true;
    *probability = fr;
    *value = Spectrum(fr);
    return fr > 0;
  }
  if (fr >= 1 || wi.z == 0) return false;
  const float etaTI = wo.z > 0 ? eta : 1 / eta;
  *reflection = false;
  *probability = 1 - fr;
  // As sample(): radiance is compressed by (eta_i / eta_t)^2 entering the denser side.
  *value = Spectrum((1 - fr) * (mode == TransportMode::Radiance ? 1 / (etaTI * etaTI) : 1.0f));
  return true;
}

float SmoothDielectricBsdf::diracJacobian(const Vec3f& a, const Vec3f& b) const {
  if (a.z * b.z >= 0) return 1;  // reflection
  const float etaA = a.z > 0 ? extIOR_ : intIOR_;
  const float etaB = b.z > 0 ? extIOR_ : intIOR_;
  return (etaB * etaB * std::fabs(b.z)) / (etaA * etaA * std::fabs(a.z));
}

// Walter et al. 2007: reflection (eq. 20) and transmission (eq. 21) through microfacets of a
// dielectric interface. Eq. 21 is the radiance form, with eta_o^2 (wo's side) in the numerator;
// the adjoint BSDF for importance, f*(wo, wi) = f(wi, wo), has eta_i^2 instead (Veach 1997,
// eq. 5.14: f / eta_o^2 is symmetric).
Spectrum RoughDielectricBsdf::eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const {
  if (wo.z == 0 || wi.z == 0) return Spectrum(0.0f);
  const float eta = intIOR_ / extIOR_;
  float cosT;
  if (wo.z * wi.z > 0) {
    Vec3f h;
    if (!reflectionHalfVector(wo, wi, &h)) return Spectrum(0.0f);
    const float d = facets_.D(h);
    if (d == 0) return Spectrum(0.0f);
    const float g = facets_.G1(wo, h) * facets_.G1(wi, h);
    const float f = fresnelDielectric(dot(wo, h), eta, &cosT);
    return Spectrum(f * d * g / (4 * std::fabs(wo.z) * std::fabs(wi.z)));
  }
  const float etaO = sideIor(wo), etaI = sideIor(wi);
  const Vec3f h = transmissionHalfVector(wo, wi, etaO, etaI);
  const float woh = dot(wo, h), wih = dot(wi, h);
  if (woh * wih >= 0) return Spectrum(0.0f);  // both on one side of the facet: no refraction
  const float d = facets_.D(h);
  const float g = facets_.G1(wo, h) * facets_.G1(wi, h);
  if (d == 0 || g == 0) return Spectrum(0.0f);
  const float f = fresnelOfRefraction(woh, etaO, wih, etaI);
  const float denom = etaO * woh + etaI * wih;
  const float etaX = mode == TransportMode::Radiance ? etaO : etaI;
  return Spectrum(std::fabs(woh * wih) * etaX * etaX * (1 - f) * d * g /
                  (std::fabs(wo.z * wi.z) * denom * denom));
}

// The density of sample(): a facet m facing wo (Microfacet::sample), then reflection with
// probability F(wo.m) (Jacobian 1 / (4 |wo.m|), eq. 14) or refraction (Jacobian
// eta_i^2 |wi.m| / (eta_o wo.m + eta_i wi.m)^2, eq. 17).
float RoughDielectricBsdf::pdf(const Vec3f& wo, const Vec3f& wi) const {
  if (wo.z == 0 || wi.z == 0) return 0;
  const float eta = intIOR_ / extIOR_;
  float cosT;
  if (wo.z * wi.z > 0) {
    Vec3f h;
    if (!reflectionHalfVector(wo, wi, &h)) return 0;
    const float woh = dot(wo, h);
    if (woh * wo.z <= 0) return 0;  // sample() draws only facets that face wo
    const float f = fresnelDielectric(woh, eta, &cosT);
    return f * facets_.pdf(wo, h) / (4 * std::fabs(woh));
  }
  const float etaO = sideIor(wo), etaI = sideIor(wi);
  const Vec3f h = transmissionHalfVector(wo, wi, etaO, etaI);
  const float woh = dot(wo, h), wih = dot(wi, h);
  if (woh * wo.z <= 0 || wih * wi.z <= 0) return 0;
  const float f = fresnelOfRefraction(woh, etaO, wih, etaI);
  const float denom = etaO * woh + etaI * wih;
  return (1 - f) * facets_.pdf(wo, h) * etaI * etaI * std::fabs(wih) / (denom * denom);
}

bool RoughDielectricBsdf::sample(const Vec3f& wo, const float u[3], TransportMode mode,
                                 BsdfSample* out) const {
  if (wo.z == 0) return false;
  const float eta = intIOR_ / extIOR_;
  const Vec3f m = facets_.sample(wo, u[1], u[2]);
  const float woh = dot(wo, m);
  if (woh * wo.z <= 0) return false;
  float cosT;
  const float f = fresnelDielectric(woh, eta, &cosT);
  const float pm = facets_.pdf(wo, m);
  // As for the rough conductor, the weight f cos / pdf in closed form from m: D and the Fresnel
  // choice cancel (Microfacet::weight).
  out->delta = false;
  if (u[0] < f) {
    const Vec3f wi = reflect(wo, m);
    if (wi.z * wo.z <= 0) return false;
    out->wi = wi;
    out->pdf = f * pm / (4 * std::fabs(woh));
    out->weight = Spectrum(facets_.weight(wo, wi, m));
    return out->pdf > 0 && isValidRadiance(out->weight);
  }
  const float etaTI = woh > 0 ? eta : 1 / eta;  // transmitted side / incident side
  const Vec3f wi = refractedAbout(wo, m, etaTI, cosT);
  if (wi.z * wo.z >= 0) return false;
  const float etaO = sideIor(wo), etaI = sideIor(wi);
  const float wih = dot(wi, m);
  const float denom = etaO * woh + etaI * wih;
  out->wi = wi;
  // The density as pdf() computes it (the choice above differs from it by rounding only).
  out->pdf = (1 - fresnelOfRefraction(woh, etaO, wih, etaI)) * pm * etaI * etaI * std::fabs(wih) /
             (denom * denom);
  // Radiance is compressed by (eta_o / eta_i)^2 crossing into the denser side, importance not
  // (as for the smooth dielectric).
  const float scale = mode == TransportMode::Radiance ? (etaO * etaO) / (etaI * etaI) : 1.0f;
  out->weight = Spectrum(scale * facets_.weight(wo, wi, m));
  return out->pdf > 0 && isValidRadiance(out->weight);
}

}  // namespace farm
