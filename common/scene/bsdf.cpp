#include "common/scene/bsdf.h"

#include <cmath>

#include "common/sampling/warp.h"

namespace farm {

namespace {

// --- Microfacet distributions (Walter et al. 2007, "Microfacet models for refraction") ---

float microfacetD(MicrofacetDistribution dist, float alpha, const Vec3f& m) {
  float c = m.z;
  if (c <= 0) return 0;
  float c2 = c * c;
  // sin^2 from the tangential components: 1 - cos^2 cancels catastrophically in float for the
  // narrow lobes (alpha down to 1e-4) where theta_m is tiny.
  float tan2 = (m.x * m.x + m.y * m.y) / c2;
  float a2 = alpha * alpha;
  if (dist == MicrofacetDistribution::Beckmann) {
    // eq. 25
    return std::exp(-tan2 / a2) / (kPi * a2 * c2 * c2);
  }
  // GGX, eq. 33
  float root = a2 + tan2;
  return a2 / (kPi * c2 * c2 * root * root);
}

// Smith's monodirectional shadowing G1(v, m) (eq. 27 with the rational fit, and eq. 34).
float smithG1(MicrofacetDistribution dist, float alpha, const Vec3f& v, const Vec3f& m) {
  if (dot(v, m) * v.z <= 0) return 0;
  float sin2 = v.x * v.x + v.y * v.y;
  if (sin2 == 0) return 1;
  float tanTheta = std::sqrt(sin2) / std::fabs(v.z);
  if (dist == MicrofacetDistribution::Beckmann) {
    float a = 1 / (alpha * tanTheta);
    if (a >= 1.6f) return 1;
    return (3.535f * a + 2.181f * a * a) / (1 + 2.276f * a + 2.577f * a * a);
  }
  float at = alpha * tanTheta;
  return 2 / (1 + std::sqrt(1 + at * at));
}

// Samples a microfacet normal with density D(m) cos(theta_m).
Vec3f sampleMicrofacet(MicrofacetDistribution dist, float alpha, float u1, float u2) {
  float tan2;
  if (dist == MicrofacetDistribution::Beckmann) {
    tan2 = -alpha * alpha * std::log1p(-u1);
  } else {
    tan2 = alpha * alpha * u1 / (1 - u1);
  }
  float cosTheta = 1 / std::sqrt(1 + tan2);
  float sinTheta = std::sqrt(tan2) * cosTheta;  // not sqrt(1 - cos^2): see microfacetD
  float phi = 2 * kPi * u2;
  return {sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta};
}

Vec3f reflect(const Vec3f& wo, const Vec3f& m) {
  return 2 * dot(wo, m) * m - wo;
}

// Snell's law about the local normal (0, 0, 1): wo refracted into the other side, with etaTI
// the index ratio transmitted side / incident side and cosT the refracted cosine (>= 0).
Vec3f refracted(const Vec3f& wo, float etaTI, float cosT) {
  float side = wo.z > 0 ? 1.0f : -1.0f;
  return normalize(-wo / etaTI + Vec3f(0, 0, side * (std::fabs(wo.z) / etaTI - cosT)));
}

}  // namespace

float fresnelDielectric(float cosThetaI, float eta, float* cosThetaT) {
  if (cosThetaI < 0) {
    eta = 1 / eta;
    cosThetaI = -cosThetaI;
  }
  float sin2T = (1 - cosThetaI * cosThetaI) / (eta * eta);
  if (sin2T >= 1) {  // total internal reflection
    *cosThetaT = 0;
    return 1;
  }
  float cosT = std::sqrt(std::max(0.0f, 1 - sin2T));
  *cosThetaT = cosT;
  float rs = (cosThetaI - eta * cosT) / (cosThetaI + eta * cosT);
  float rp = (eta * cosThetaI - cosT) / (eta * cosThetaI + cosT);
  return 0.5f * (rs * rs + rp * rp);
}

Spectrum fresnelConductor(float cosThetaI, const Spectrum& eta, const Spectrum& k) {
  // Exact unpolarized Fresnel reflectance of a conductor (e.g. Born and Wolf, sec. 14.2).
  float c = std::min(1.0f, std::fabs(cosThetaI));
  float c2 = c * c, s2 = 1 - c2, s4 = s2 * s2;
  Spectrum result;
  for (int i = 0; i < 3; ++i) {
    float e = eta[i], kk = k[i];
    float temp = e * e - kk * kk - s2;
    float a2pb2 = std::sqrt(std::max(0.0f, temp * temp + 4 * kk * kk * e * e));
    float a = std::sqrt(std::max(0.0f, 0.5f * (a2pb2 + temp)));
    float term1 = a2pb2 + c2, term2 = 2 * a * c;
    float rs = (term1 - term2) / (term1 + term2);
    float term3 = a2pb2 * c2 + s4, term4 = term2 * s2;
    float rp = rs * (term3 - term4) / (term3 + term4);
    result[i] = 0.5f * (rp + rs);
  }
  return result;
}

Bsdf::Bsdf(const BsdfDescription& desc) : desc_(desc), type_(desc.type) {}

bool Bsdf::isBlack() const {
  switch (type_) {
    case BsdfDescription::Type::Diffuse:
      return farm::isBlack(desc_.reflectance);
    case BsdfDescription::Type::RoughConductor:
      return farm::isBlack(desc_.specularReflectance);
    case BsdfDescription::Type::Dielectric:
      return false;
  }
  return false;
}

Spectrum Bsdf::eval(const Vec3f& woIn, const Vec3f& wiIn, TransportMode) const {
  Vec3f wo = woIn, wi = wiIn;
  if (desc_.twoSided && wo.z < 0) {  // twosided: the back side behaves as the front
    wo.z = -wo.z;
    wi.z = -wi.z;
  }
  switch (type_) {
    case BsdfDescription::Type::Diffuse:
      if (wo.z <= 0 || wi.z <= 0) return Spectrum(0.0f);
      return desc_.reflectance * kInvPi;
    case BsdfDescription::Type::RoughConductor: {
      if (wo.z <= 0 || wi.z <= 0) return Spectrum(0.0f);
      Vec3f h = wo + wi;
      float hl = length(h);
      if (hl == 0) return Spectrum(0.0f);
      h = h / hl;
      float d = microfacetD(desc_.distribution, desc_.alpha, h);
      if (d == 0) return Spectrum(0.0f);
      float g = smithG1(desc_.distribution, desc_.alpha, wo, h) *
                smithG1(desc_.distribution, desc_.alpha, wi, h);
      Spectrum f = fresnelConductor(dot(wo, h), desc_.eta / desc_.extEta, desc_.k / desc_.extEta);
      return desc_.specularReflectance * f * (d * g / (4 * wo.z * wi.z));
    }
    case BsdfDescription::Type::Dielectric:
      return Spectrum(0.0f);
  }
  return Spectrum(0.0f);
}

float Bsdf::pdf(const Vec3f& woIn, const Vec3f& wiIn) const {
  Vec3f wo = woIn, wi = wiIn;
  if (desc_.twoSided && wo.z < 0) {
    wo.z = -wo.z;
    wi.z = -wi.z;
  }
  switch (type_) {
    case BsdfDescription::Type::Diffuse:
      if (wo.z <= 0 || wi.z <= 0) return 0;
      return cosineHemispherePdf(wi.z);
    case BsdfDescription::Type::RoughConductor: {
      if (wo.z <= 0 || wi.z <= 0) return 0;
      Vec3f h = wo + wi;
      float hl = length(h);
      if (hl == 0) return 0;
      h = h / hl;
      // density of m is D(m) cos(theta_m); the reflection Jacobian is 1 / (4 |wo.m|) (eq. 14)
      return microfacetD(desc_.distribution, desc_.alpha, h) * h.z / (4 * absDot(wo, h));
    }
    case BsdfDescription::Type::Dielectric:
      return 0;
  }
  return 0;
}

bool Bsdf::sample(const Vec3f& woIn, const float u[3], TransportMode mode, BsdfSample* out) const {
  Vec3f wo = woIn;
  bool flipped = false;
  if (desc_.twoSided && wo.z < 0) {
    wo.z = -wo.z;
    flipped = true;
  }
  switch (type_) {
    case BsdfDescription::Type::Diffuse: {
      if (wo.z <= 0) return false;
      Vec3f wi = squareToCosineHemisphere({u[1], u[2]});
      if (wi.z <= 0) return false;
      out->wi = flipped ? Vec3f(wi.x, wi.y, -wi.z) : wi;
      out->pdf = cosineHemispherePdf(wi.z);
      out->weight = desc_.reflectance;
      out->delta = false;
      return true;
    }
    case BsdfDescription::Type::RoughConductor: {
      if (wo.z <= 0) return false;
      Vec3f m = sampleMicrofacet(desc_.distribution, desc_.alpha, u[1], u[2]);
      float womDot = dot(wo, m);
      if (womDot <= 0) return false;
      Vec3f wi = reflect(wo, m);
      if (wi.z <= 0) return false;
      float pdf = microfacetD(desc_.distribution, desc_.alpha, m) * m.z / (4 * womDot);
      if (!(pdf > 0)) return false;
      // The weight f cos / pdf in closed form from the sampled normal m (Walter et al. 2007,
      // eq. 38): D cancels, so it stays exact where recomputing the half vector from float
      // directions would not (tiny alpha at grazing angles).
      float g = smithG1(desc_.distribution, desc_.alpha, wo, m) *
                smithG1(desc_.distribution, desc_.alpha, wi, m);
      Spectrum fr = fresnelConductor(womDot, desc_.eta / desc_.extEta, desc_.k / desc_.extEta);
      out->wi = flipped ? Vec3f(wi.x, wi.y, -wi.z) : wi;
      out->pdf = pdf;
      out->weight = desc_.specularReflectance * fr * (g * womDot / (wo.z * m.z));
      out->delta = false;
      return isValidRadiance(out->weight);
    }
    case BsdfDescription::Type::Dielectric: {
      float eta = desc_.intIOR / desc_.extIOR;
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
  }
  return false;
}

bool Bsdf::specularDirection(const Vec3f& wo, bool reflection, Vec3f* wi) const {
  if (type_ != BsdfDescription::Type::Dielectric || wo.z == 0) return false;
  if (reflection) {
    *wi = Vec3f(-wo.x, -wo.y, wo.z);
    return true;
  }
  float eta = desc_.intIOR / desc_.extIOR, cosT;
  if (fresnelDielectric(wo.z, eta, &cosT) >= 1) return false;  // total internal reflection
  *wi = refracted(wo, wo.z > 0 ? eta : 1 / eta, cosT);
  return true;
}

bool Bsdf::specularLobe(const Vec3f& wo, const Vec3f& wi, TransportMode mode, bool* reflection,
                        float* probability, Spectrum* value) const {
  if (type_ != BsdfDescription::Type::Dielectric || wo.z == 0) return false;
  const float eta = desc_.intIOR / desc_.extIOR;
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

float Bsdf::diracJacobian(const Vec3f& a, const Vec3f& b) const {
  if (a.z * b.z >= 0) return 1;  // reflection
  const float etaA = a.z > 0 ? desc_.extIOR : desc_.intIOR;
  const float etaB = b.z > 0 ? desc_.extIOR : desc_.intIOR;
  return (etaB * etaB * std::fabs(b.z)) / (etaA * etaA * std::fabs(a.z));
}

}  // namespace farm
