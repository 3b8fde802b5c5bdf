#include "common/scene/bsdfs/coated_diffuse.h"

#include <stdexcept>

namespace farm {

CoatedDiffuseBsdf::CoatedDiffuseBsdf(const BsdfDescription& desc)
    : reflectance_(desc.reflectance),
      glossy_(desc),
      eta_(desc.intIOR / desc.extIOR),
      nonlinear_(desc.nonlinear),
      coating_(desc.coating.get()),
      coatingShare_(desc.coating) {
  if (!coating_)
    throw std::invalid_argument("a coated diffuse BSDF needs its coating transmittance");
}

CoatedDiffuseBsdf::CoatedDiffuseBsdf(const CoatedDiffuseBsdf& other)
    : reflectance_(other.reflectance_),
      glossy_(other.glossy_),
      eta_(other.eta_),
      nonlinear_(other.nonlinear_),
      coating_(other.coating_) {}

CoatedDiffuseBsdf& CoatedDiffuseBsdf::operator=(const CoatedDiffuseBsdf& other) {
  reflectance_ = other.reflectance_;
  glossy_ = other.glossy_;
  eta_ = other.eta_;
  nonlinear_ = other.nonlinear_;
  coating_ = other.coating_;
  coatingShare_.reset();
  return *this;
}

// Light enters through the coat (T(mu_i)), reaches the Lambertian base, bounces between base
// and coat (each time the coat reflects Fdr of it back down: the geometric series
// 1 / (1 - rho Fdr), or Mitsuba's default 1 / (1 - Fdr), which keeps the base's colour), leaves
// through the coat (T(mu_o)); the radiance inside is eta^2 times that outside, hence 1 / eta^2.
Spectrum CoatedDiffuseBsdf::base(const Vec3f& wo, const Vec3f& wi) const {
  const float fdr = coating_->internalDiffuseReflectance();
  const Spectrum& rho = reflectance_;
  Spectrum base;
  for (int c = 0; c < 3; ++c) base[c] = rho[c] / (1 - (nonlinear_ ? rho[c] : 1.0f) * fdr);
  return base *
         (coating_->fromOutside(wo.z) * coating_->fromOutside(wi.z) * kInvPi / (eta_ * eta_));
}

// Mitsuba's choice: the coat's own reflectance 1 - T(mu_o) against what it lets through,
// weighted by the lobes' reflectances.
float CoatedDiffuseBsdf::glossyProbability(const Vec3f& wo) const {
  const float g = luminance(glossy_.specularReflectance()), d = luminance(reflectance_);
  if (d <= 0) return 1;
  if (g <= 0) return 0;
  const float s = g / (g + d), r = 1 - coating_->fromOutside(wo.z);
  return s * r / (s * r + (1 - s) * (1 - r));
}

Spectrum CoatedDiffuseBsdf::eval(const Vec3f& wo, const Vec3f& wi, TransportMode) const {
  if (wo.z <= 0 || wi.z <= 0) return Spectrum(0.0f);
  return base(wo, wi) + glossy_.eval(wo, wi);
}

float CoatedDiffuseBsdf::pdf(const Vec3f& wo, const Vec3f& wi) const {
  return diffuseOrGlossyPdf(1 - glossyProbability(wo), glossy_, wo, wi);
}

bool CoatedDiffuseBsdf::sample(const Vec3f& wo, const float u[3], TransportMode mode,
                               BsdfSample* out) const {
  return sampleDiffuseOrGlossy(*this, 1 - glossyProbability(wo), glossy_, wo, u, mode, out);
}

bool CoatedDiffuseBsdf::isBlack() const {
  return farm::isBlack(reflectance_) && farm::isBlack(glossy_.specularReflectance());
}

}  // namespace farm
