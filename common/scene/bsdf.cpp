#include "common/scene/bsdf.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <mutex>
#include <stdexcept>
#include <tuple>

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

// Samples a GGX normal visible from w (w.z > 0) with density G1(w, m) max(0, w.m) D(m) / w.z
// (Heitz 2018, "Sampling the GGX distribution of visible normals"): stretch w to the unit
// roughness configuration, sample the projected hemisphere there, and unstretch the normal.
Vec3f sampleVisibleGgx(float alpha, const Vec3f& w, float u1, float u2) {
  const Vec3f v = normalize(Vec3f(alpha * w.x, alpha * w.y, w.z));
  const float len2 = v.x * v.x + v.y * v.y;
  const Vec3f t1 = len2 > 0 ? Vec3f(-v.y, v.x, 0) / std::sqrt(len2) : Vec3f(1, 0, 0);
  const Vec3f t2 = cross(v, t1);
  const float r = std::sqrt(u1), phi = 2 * kPi * u2;
  const float p1 = r * std::cos(phi);
  const float s = 0.5f * (1 + v.z);
  const float p2 = (1 - s) * std::sqrt(std::max(0.0f, 1 - p1 * p1)) + s * r * std::sin(phi);
  const Vec3f n = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1 - p1 * p1 - p2 * p2)) * v;
  return normalize(Vec3f(alpha * n.x, alpha * n.y, std::max(1e-7f, n.z)));
}

// The microfacet normal a BSDF samples for wo (of either side): GGX normals visible from wo,
// Beckmann normals by D(m) cos(theta_m). Always m.z > 0.
Vec3f sampleFacet(MicrofacetDistribution dist, float alpha, const Vec3f& wo, float u1, float u2) {
  if (dist == MicrofacetDistribution::Beckmann) return sampleMicrofacet(dist, alpha, u1, u2);
  return sampleVisibleGgx(alpha, wo.z > 0 ? wo : -wo, u1, u2);
}

// The density of sampleFacet's m (facing wo).
float facetPdf(MicrofacetDistribution dist, float alpha, const Vec3f& wo, const Vec3f& m) {
  const float d = microfacetD(dist, alpha, m);
  if (dist == MicrofacetDistribution::Beckmann) return d * m.z;
  return smithG1(dist, alpha, wo, m) * std::fabs(dot(wo, m)) * d / std::fabs(wo.z);
}

// What is left of f |cos(theta_i)| / pdf for a facet m sampled by sampleFacet, once D, the
// Fresnel term (and, for refraction, the eta factors and Jacobians) cancel: G1(wo, m) G1(wi, m)
// |wo.m| / (|wo.z| m.z) for Beckmann (Walter et al. 2007, eq. 41), and G1(wi, m) for visible
// GGX normals. In closed form from m, so it stays exact where recomputing the half vector from
// float directions would not (tiny alpha at grazing angles).
float facetWeight(MicrofacetDistribution dist, float alpha, const Vec3f& wo, const Vec3f& wi,
                  const Vec3f& m) {
  if (dist == MicrofacetDistribution::GGX) return smithG1(dist, alpha, wi, m);
  return smithG1(dist, alpha, wo, m) * smithG1(dist, alpha, wi, m) * std::fabs(dot(wo, m)) /
         (std::fabs(wo.z) * m.z);
}

Vec3f reflect(const Vec3f& wo, const Vec3f& m) {
  return 2 * dot(wo, m) * m - wo;
}

// The half vector of a reflection (Walter et al. 2007, eq. 13), oriented to +z; false when wo
// and wi are opposite and there is none.
bool reflectionHalfVector(const Vec3f& wo, const Vec3f& wi, Vec3f* h) {
  const Vec3f sum = wo + wi;
  const float l = length(sum);
  if (!(l > 0)) return false;
  *h = sum.z < 0 ? -sum / l : sum / l;
  return true;
}

// Snell's law about the local normal (0, 0, 1): wo refracted into the other side, with etaTI
// the index ratio transmitted side / incident side and cosT the refracted cosine (>= 0).
Vec3f refracted(const Vec3f& wo, float etaTI, float cosT) {
  float side = wo.z > 0 ? 1.0f : -1.0f;
  return normalize(-wo / etaTI + Vec3f(0, 0, side * (std::fabs(wo.z) / etaTI - cosT)));
}

// Snell's law about a microfacet normal m (Walter et al. 2007, eq. 40): wo refracted through
// the facet, with etaTI = eta_t / eta_i and cosT the refracted cosine to m (>= 0).
Vec3f refractedAbout(const Vec3f& wo, const Vec3f& m, float etaTI, float cosT) {
  const float c = dot(wo, m);
  return normalize(-wo / etaTI + m * (c / etaTI - (c > 0 ? cosT : -cosT)));
}

// The indices of refraction on the sides of the interface that local directions point into.
float sideIor(const BsdfDescription& d, const Vec3f& w) {
  return w.z > 0 ? d.extIOR : d.intIOR;
}

// A rough dielectric's transmission at half vector m (Walter et al. 2007, eq. 16), from eta_o
// on wo's side and eta_i on wi's: the generalized half vector, oriented to +z.
Vec3f transmissionHalfVector(const Vec3f& wo, const Vec3f& wi, float etaO, float etaI) {
  Vec3f h = -(etaO * wo + etaI * wi);
  const float l = length(h);
  if (!(l > 0)) return Vec3f(0.0f);
  h = h / l;
  return h.z < 0 ? -h : h;
}

// The Fresnel reflectance of a refraction whose two cosines are known (to the facet, each on its
// own side, with that side's index): symmetric in the two sides, so a refraction and its
// reverse get the same value, and well-conditioned near the critical angle, where recovering
// the refracted cosine from the incident one loses the digits that 1 - F is made of.
float fresnelOfRefraction(float cosA, float etaA, float cosB, float etaB) {
  cosA = std::fabs(cosA), cosB = std::fabs(cosB);
  const float rs = (etaA * cosA - etaB * cosB) / (etaA * cosA + etaB * cosB);
  const float rp = (etaB * cosA - etaA * cosB) / (etaB * cosA + etaA * cosB);
  return 0.5f * (rs * rs + rp * rp);
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

Bsdf::Bsdf(const BsdfDescription& desc) : desc_(desc), type_(desc.type) {
  // Scene::bsdfAt copies a Bsdf for every shading point of a textured material; without the
  // name, that copy never allocates, and without the shared coating it touches no shared count.
  desc_.id.clear();
  desc_.id.shrink_to_fit();
  if (type_ == BsdfDescription::Type::CoatedDiffuse) {
    if (!desc.coating)
      throw std::invalid_argument("a coated diffuse BSDF needs its coating transmittance");
    coatingShare_ = desc.coating;
    coating_ = coatingShare_.get();
  }
  desc_.coating.reset();
}

Bsdf::Bsdf(const Bsdf& other) : desc_(other.desc_), type_(other.type_), coating_(other.coating_) {}

Bsdf& Bsdf::operator=(const Bsdf& other) {
  desc_ = other.desc_;
  type_ = other.type_;
  coating_ = other.coating_;
  coatingShare_.reset();
  return *this;
}

void Bsdf::setReflectance(const Spectrum& reflectance) {
  desc_.reflectance = reflectance;
}

bool Bsdf::isBlack() const {
  switch (type_) {
    case BsdfDescription::Type::Diffuse:
      return farm::isBlack(desc_.reflectance);
    case BsdfDescription::Type::Conductor:
    case BsdfDescription::Type::RoughConductor:
      return farm::isBlack(desc_.specularReflectance);
    case BsdfDescription::Type::Dielectric:
    case BsdfDescription::Type::RoughDielectric:
      return false;
    case BsdfDescription::Type::Plastic:
    case BsdfDescription::Type::CoatedDiffuse:
      return farm::isBlack(desc_.reflectance) && farm::isBlack(desc_.specularReflectance);
  }
  return false;
}

// pbrt-v3's plastic is the sum of a Lambertian lobe and a Torrance-Sparrow lobe whose Fresnel
// term is a dielectric's: nothing couples them (Kd + Ks <= 1 keeps it energy-conserving).
// Both lobes are sampled, each in proportion to its reflectance's luminance; the density is
// the mixture's (the one-sample model of Veach 1997, 9.2.4), so eval cos / pdf is the weight.
float Bsdf::plasticDiffuseProbability() const {
  const float d = luminance(desc_.reflectance), g = luminance(desc_.specularReflectance);
  return d + g > 0 ? d / (d + g) : 0.5f;
}

float Bsdf::diffuseProbability(const Vec3f& wo) const {
  return type_ == BsdfDescription::Type::Plastic ? plasticDiffuseProbability()
                                                 : 1 - coatedGlossyProbability(wo);
}

// The coated base (Mitsuba's roughplastic; Weidlich and Wilkie 2007 for the smooth case): light
// enters through the coat (T(mu_i)), reaches the Lambertian base, bounces between base and coat
// (each time the coat reflects Fdr of it back down: the geometric series 1 / (1 - rho Fdr), or
// Mitsuba's default 1 / (1 - Fdr), which keeps the base's colour), leaves through the coat
// (T(mu_o)); the radiance inside is eta^2 times that outside, hence the 1 / eta^2.
Spectrum Bsdf::coatedBase(const Vec3f& wo, const Vec3f& wi) const {
  const float eta = desc_.intIOR / desc_.extIOR;
  const float fdr = coating_->internalDiffuseReflectance();
  const Spectrum& rho = desc_.reflectance;
  Spectrum base;
  for (int c = 0; c < 3; ++c) base[c] = rho[c] / (1 - (desc_.nonlinear ? rho[c] : 1.0f) * fdr);
  return base * (coating_->fromOutside(wo.z) * coating_->fromOutside(wi.z) * kInvPi / (eta * eta));
}

// Mitsuba's choice: the coat's own reflectance 1 - T(mu_o) against what it lets through,
// weighted by the lobes' reflectances.
float Bsdf::coatedGlossyProbability(const Vec3f& wo) const {
  const float g = luminance(desc_.specularReflectance), d = luminance(desc_.reflectance);
  if (d <= 0) return 1;
  if (g <= 0) return 0;
  const float s = g / (g + d), r = 1 - coating_->fromOutside(wo.z);
  return s * r / (s * r + (1 - s) * (1 - r));
}

Spectrum Bsdf::plasticGlossy(const Vec3f& wo, const Vec3f& wi) const {
  Vec3f h;
  if (wo.z <= 0 || wi.z <= 0 || !reflectionHalfVector(wo, wi, &h)) return Spectrum(0.0f);
  const float d = microfacetD(desc_.distribution, desc_.alpha, h);
  if (d == 0) return Spectrum(0.0f);
  const float g = smithG1(desc_.distribution, desc_.alpha, wo, h) *
                  smithG1(desc_.distribution, desc_.alpha, wi, h);
  float cosT;
  const float f = fresnelDielectric(dot(wo, h), desc_.intIOR / desc_.extIOR, &cosT);
  return desc_.specularReflectance * (f * d * g / (4 * wo.z * wi.z));
}

bool Bsdf::isDelta() const {
  return type_ == BsdfDescription::Type::Dielectric || type_ == BsdfDescription::Type::Conductor;
}

Spectrum Bsdf::conductorFresnel(float cosThetaI) const {
  return desc_.specularReflectance *
         fresnelConductor(cosThetaI, desc_.eta / desc_.extEta, desc_.k / desc_.extEta);
}

// Walter et al. 2007: reflection (eq. 20) and transmission (eq. 21) through microfacets of a
// dielectric interface. Eq. 21 is the radiance form, with eta_o^2 (wo's side) in the numerator;
// the adjoint BSDF for importance, f*(wo, wi) = f(wi, wo), has eta_i^2 instead (Veach 1997,
// eq. 5.14: f / eta_o^2 is symmetric).
Spectrum Bsdf::roughDielectricEval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const {
  if (wo.z == 0 || wi.z == 0) return Spectrum(0.0f);
  const float eta = desc_.intIOR / desc_.extIOR;
  const MicrofacetDistribution dist = desc_.distribution;
  const float alpha = desc_.alpha;
  float cosT;
  if (wo.z * wi.z > 0) {
    Vec3f h;
    if (!reflectionHalfVector(wo, wi, &h)) return Spectrum(0.0f);
    const float d = microfacetD(dist, alpha, h);
    if (d == 0) return Spectrum(0.0f);
    const float g = smithG1(dist, alpha, wo, h) * smithG1(dist, alpha, wi, h);
    const float f = fresnelDielectric(dot(wo, h), eta, &cosT);
    return Spectrum(f * d * g / (4 * std::fabs(wo.z) * std::fabs(wi.z)));
  }
  const float etaO = sideIor(desc_, wo), etaI = sideIor(desc_, wi);
  const Vec3f h = transmissionHalfVector(wo, wi, etaO, etaI);
  const float woh = dot(wo, h), wih = dot(wi, h);
  if (woh * wih >= 0) return Spectrum(0.0f);  // both on one side of the facet: no refraction
  const float d = microfacetD(dist, alpha, h);
  const float g = smithG1(dist, alpha, wo, h) * smithG1(dist, alpha, wi, h);
  if (d == 0 || g == 0) return Spectrum(0.0f);
  const float f = fresnelOfRefraction(woh, etaO, wih, etaI);
  const float denom = etaO * woh + etaI * wih;
  const float etaX = mode == TransportMode::Radiance ? etaO : etaI;
  return Spectrum(std::fabs(woh * wih) * etaX * etaX * (1 - f) * d * g /
                  (std::fabs(wo.z * wi.z) * denom * denom));
}

// The density of roughDielectricSample: a facet m facing wo with sampleFacet's density
// (facetPdf: visible normals for GGX, D(m) cos(theta_m) for Beckmann), then
// reflection with probability F(wo.m) (Jacobian 1 / (4 |wo.m|), eq. 14) or refraction
// (Jacobian eta_i^2 |wi.m| / (eta_o wo.m + eta_i wi.m)^2, eq. 17).
float Bsdf::roughDielectricPdf(const Vec3f& wo, const Vec3f& wi) const {
  if (wo.z == 0 || wi.z == 0) return 0;
  const float eta = desc_.intIOR / desc_.extIOR;
  const MicrofacetDistribution dist = desc_.distribution;
  float cosT;
  if (wo.z * wi.z > 0) {
    Vec3f h;
    if (!reflectionHalfVector(wo, wi, &h)) return 0;
    const float woh = dot(wo, h);
    if (woh * wo.z <= 0) return 0;  // sample() draws only facets that face wo
    const float f = fresnelDielectric(woh, eta, &cosT);
    return f * facetPdf(dist, desc_.alpha, wo, h) / (4 * std::fabs(woh));
  }
  const float etaO = sideIor(desc_, wo), etaI = sideIor(desc_, wi);
  const Vec3f h = transmissionHalfVector(wo, wi, etaO, etaI);
  const float woh = dot(wo, h), wih = dot(wi, h);
  if (woh * wo.z <= 0 || wih * wi.z <= 0) return 0;
  const float f = fresnelOfRefraction(woh, etaO, wih, etaI);
  const float denom = etaO * woh + etaI * wih;
  return (1 - f) * facetPdf(dist, desc_.alpha, wo, h) * etaI * etaI * std::fabs(wih) /
         (denom * denom);
}

bool Bsdf::roughDielectricSample(const Vec3f& wo, const float u[3], TransportMode mode,
                                 BsdfSample* out) const {
  if (wo.z == 0) return false;
  const float eta = desc_.intIOR / desc_.extIOR;
  const MicrofacetDistribution dist = desc_.distribution;
  const float alpha = desc_.alpha;
  const Vec3f m = sampleFacet(dist, alpha, wo, u[1], u[2]);
  const float woh = dot(wo, m);
  if (woh * wo.z <= 0) return false;
  float cosT;
  const float f = fresnelDielectric(woh, eta, &cosT);
  const float pm = facetPdf(dist, alpha, wo, m);
  // As for the rough conductor, the weight f cos / pdf in closed form from m: D and the Fresnel
  // choice cancel (facetWeight).
  out->delta = false;
  if (u[0] < f) {
    const Vec3f wi = reflect(wo, m);
    if (wi.z * wo.z <= 0) return false;
    out->wi = wi;
    out->pdf = f * pm / (4 * std::fabs(woh));
    out->weight = Spectrum(facetWeight(dist, alpha, wo, wi, m));
    return out->pdf > 0 && isValidRadiance(out->weight);
  }
  const float etaTI = woh > 0 ? eta : 1 / eta;  // transmitted side / incident side
  const Vec3f wi = refractedAbout(wo, m, etaTI, cosT);
  if (wi.z * wo.z >= 0) return false;
  const float etaO = sideIor(desc_, wo), etaI = sideIor(desc_, wi);
  const float wih = dot(wi, m);
  const float denom = etaO * woh + etaI * wih;
  out->wi = wi;
  // The density as pdf() computes it (the choice above differs from it by rounding only).
  out->pdf = (1 - fresnelOfRefraction(woh, etaO, wih, etaI)) * pm * etaI * etaI * std::fabs(wih) /
             (denom * denom);
  // Radiance is compressed by (eta_o / eta_i)^2 crossing into the denser side, importance not
  // (as for the smooth dielectric).
  const float scale = mode == TransportMode::Radiance ? (etaO * etaO) / (etaI * etaI) : 1.0f;
  out->weight = Spectrum(scale * facetWeight(dist, alpha, wo, wi, m));
  return out->pdf > 0 && isValidRadiance(out->weight);
}

Spectrum Bsdf::eval(const Vec3f& woIn, const Vec3f& wiIn, TransportMode mode) const {
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
      Vec3f h;
      if (wo.z <= 0 || wi.z <= 0 || !reflectionHalfVector(wo, wi, &h)) return Spectrum(0.0f);
      float d = microfacetD(desc_.distribution, desc_.alpha, h);
      if (d == 0) return Spectrum(0.0f);
      float g = smithG1(desc_.distribution, desc_.alpha, wo, h) *
                smithG1(desc_.distribution, desc_.alpha, wi, h);
      return conductorFresnel(dot(wo, h)) * (d * g / (4 * wo.z * wi.z));
    }
    case BsdfDescription::Type::RoughDielectric:
      return roughDielectricEval(wo, wi, mode);
    case BsdfDescription::Type::Plastic:
      if (wo.z <= 0 || wi.z <= 0) return Spectrum(0.0f);
      return desc_.reflectance * kInvPi + plasticGlossy(wo, wi);
    case BsdfDescription::Type::CoatedDiffuse:
      if (wo.z <= 0 || wi.z <= 0) return Spectrum(0.0f);
      return coatedBase(wo, wi) + plasticGlossy(wo, wi);
    case BsdfDescription::Type::Dielectric:
    case BsdfDescription::Type::Conductor:
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
      Vec3f h;
      if (wo.z <= 0 || wi.z <= 0 || !reflectionHalfVector(wo, wi, &h)) return 0;
      // the facet's density (facetPdf); the reflection Jacobian is 1 / (4 |wo.m|) (eq. 14)
      return facetPdf(desc_.distribution, desc_.alpha, wo, h) / (4 * absDot(wo, h));
    }
    case BsdfDescription::Type::RoughDielectric:
      return roughDielectricPdf(wo, wi);
    case BsdfDescription::Type::Plastic:
    case BsdfDescription::Type::CoatedDiffuse: {
      if (wo.z <= 0 || wi.z <= 0) return 0;
      const float pd = diffuseProbability(wo);
      float pdf = pd * cosineHemispherePdf(wi.z);
      Vec3f h;
      if (reflectionHalfVector(wo, wi, &h))
        pdf += (1 - pd) * facetPdf(desc_.distribution, desc_.alpha, wo, h) / (4 * absDot(wo, h));
      return pdf;
    }
    case BsdfDescription::Type::Dielectric:
    case BsdfDescription::Type::Conductor:
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
      const Vec3f m = sampleFacet(desc_.distribution, desc_.alpha, wo, u[1], u[2]);
      const float womDot = dot(wo, m);
      if (womDot <= 0) return false;
      const Vec3f wi = reflect(wo, m);
      if (wi.z <= 0) return false;
      const float pdf = facetPdf(desc_.distribution, desc_.alpha, wo, m) / (4 * womDot);
      if (!(pdf > 0)) return false;
      out->wi = flipped ? Vec3f(wi.x, wi.y, -wi.z) : wi;
      out->pdf = pdf;
      out->weight =
          conductorFresnel(womDot) * facetWeight(desc_.distribution, desc_.alpha, wo, wi, m);
      out->delta = false;
      return isValidRadiance(out->weight);
    }
    case BsdfDescription::Type::Conductor: {
      if (wo.z <= 0) return false;
      out->wi = Vec3f(-wo.x, -wo.y, flipped ? -wo.z : wo.z);
      out->pdf = 1;
      out->weight = conductorFresnel(wo.z);
      out->delta = true;
      return !farm::isBlack(out->weight);  // as specularLobe(): no lobe carries nothing
    }
    case BsdfDescription::Type::RoughDielectric:
      return roughDielectricSample(wo, u, mode, out);
    case BsdfDescription::Type::Plastic:
    case BsdfDescription::Type::CoatedDiffuse: {
      if (wo.z <= 0) return false;
      const float pd = diffuseProbability(wo);
      Vec3f wi;
      if (u[0] < pd) {
        wi = squareToCosineHemisphere({u[1], u[2]});
      } else {
        const Vec3f m = sampleFacet(desc_.distribution, desc_.alpha, wo, u[1], u[2]);
        if (dot(wo, m) <= 0) return false;
        wi = reflect(wo, m);
      }
      if (wi.z <= 0) return false;
      const float pdf = this->pdf(wo, wi);
      if (!(pdf > 0)) return false;
      out->wi = flipped ? Vec3f(wi.x, wi.y, -wi.z) : wi;
      out->pdf = pdf;
      out->weight = eval(wo, wi, mode) * (wi.z / pdf);
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
  if (type_ == BsdfDescription::Type::Conductor) {
    if (!reflection || !(wo.z > 0 || (desc_.twoSided && wo.z < 0))) return false;
    *wi = Vec3f(-wo.x, -wo.y, wo.z);
    return true;
  }
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
  if (type_ == BsdfDescription::Type::Conductor) {
    // One lobe, chosen always; its value is the Fresnel reflectance.
    if (!(wo.z * wi.z > 0) || !(wo.z > 0 || desc_.twoSided)) return false;
    *reflection = true;
    *probability = 1;
    *value = conductorFresnel(std::fabs(wo.z));
    return !farm::isBlack(*value);
  }
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

namespace {

// T(mu) by quadrature over the facets sampleFacet draws for wo (the midpoints of an n x n grid
// of its two numbers): each facet refracts the share 1 - F(wo.m) of what it receives, and what
// is left of the refraction's f |cos| / pdf once D, the Fresnel choice and the Jacobians cancel
// is facetWeight; in energy (importance) form, with no eta^2 compression. So this is the mean
// weight of roughDielectricSample's refractions in importance form, computed without it.
double coatTransmittance(MicrofacetDistribution dist, float alpha, float eta, float mu, int n) {
  if (mu <= 0) return 0;
  const Vec3f wo(std::sqrt(std::max(0.0f, 1 - mu * mu)), 0, mu);
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const Vec3f m = sampleFacet(dist, alpha, wo, (i + 0.5f) / n, (j + 0.5f) / n);
      const float woh = dot(wo, m);
      if (woh <= 0) continue;
      float cosT;
      const float f = fresnelDielectric(woh, eta, &cosT);
      if (f >= 1) continue;
      const Vec3f wi = refractedAbout(wo, m, eta, cosT);
      if (wi.z >= 0) continue;
      sum += (1 - f) * facetWeight(dist, alpha, wo, wi, m);
    }
  }
  return sum / (double(n) * n);
}

constexpr int kCoatQuadrature = 32;  // facets per axis and table entry

}  // namespace

CoatingTransmittance::CoatingTransmittance(MicrofacetDistribution dist, float alpha, float eta) {
  if (!(alpha > 0) || !(eta > 0) || eta == 1 || !std::isfinite(alpha) || !std::isfinite(eta))
    throw std::invalid_argument("a coating needs alpha > 0 and a relative index > 0, != 1");
  outside_.resize(kResolution);
  double inside = 0;  // 2 \int T_in(mu) mu dmu by the trapezoid rule over the same mu
  for (int k = 0; k < kResolution; ++k) {
    const float mu = float(k) / (kResolution - 1);
    outside_[size_t(k)] = float(coatTransmittance(dist, alpha, eta, mu, kCoatQuadrature));
    const double weight = (k == 0 || k == kResolution - 1) ? 0.5 : 1.0;
    inside += weight * 2 * mu * coatTransmittance(dist, alpha, 1 / eta, mu, kCoatQuadrature);
  }
  inside /= (kResolution - 1);
  internalDiffuseReflectance_ = float(1 - inside);
}

std::shared_ptr<const CoatingTransmittance> sharedCoatingTransmittance(MicrofacetDistribution dist,
                                                                       float alpha, float eta) {
  static std::mutex mutex;
  static std::map<std::tuple<int, float, float>, std::weak_ptr<const CoatingTransmittance>> shared;
  const std::lock_guard<std::mutex> lock(mutex);
  const auto key = std::make_tuple(int(dist), alpha, eta);
  if (auto alive = shared[key].lock()) return alive;
  for (auto it = shared.begin(); it != shared.end();)  // forget the dead ones
    it = it->second.expired() ? shared.erase(it) : std::next(it);
  auto made = std::make_shared<const CoatingTransmittance>(dist, alpha, eta);
  shared[key] = made;
  return made;
}

float CoatingTransmittance::lookup(const std::vector<float>& table, float mu) {
  const float x = std::clamp(mu, 0.0f, 1.0f) * (kResolution - 1);
  const int k = std::min(int(x), kResolution - 2);
  const float t = x - float(k);
  return (1 - t) * table[size_t(k)] + t * table[size_t(k) + 1];
}

}  // namespace farm
