#pragma once
// Surface scattering in the local shading frame (z = normal). Directions point away from the
// surface: wo towards the previous vertex of the path being built, wi the sampled (or connected)
// next one. A small closed set of models, dispatched by type: what the Mitsuba scenes use.
#include <memory>
#include <vector>

#include "common/math/vec.h"
#include "common/scene/scene_description.h"

namespace farm {

// Which quantity a path carries: the BSDF is not symmetric under refraction (Veach 1997, 5.2).
enum class TransportMode { Radiance, Importance };

struct BsdfSample {
  Vec3f wi;
  Spectrum weight;     // f(wo, wi) |cos(wi)| / pdf
  float pdf = 0;       // solid-angle density (for a delta lobe: the discrete probability)
  bool delta = false;  // sampled from a Dirac lobe: cannot be evaluated or connected to
};

// The share of the power arriving at a rough dielectric boundary from a direction of cosine mu
// (on either side) that it transmits, T(mu), as Mitsuba's roughplastic uses it (its
// RoughTransmittance): the directional albedo of the boundary's transmission lobe, for one
// distribution, roughness and relative index. Tabulated at construction by a quadrature over
// the microfacet normals the rough dielectric samples; looked up linearly in mu.
class CoatingTransmittance {
 public:
  // eta: the index of the coat over that of the outside (> 0, != 1).
  CoatingTransmittance(MicrofacetDistribution dist, float alpha, float eta);
  // T(mu) for light arriving from outside, mu in [0, 1].
  float fromOutside(float mu) const { return lookup(outside_, mu); }
  // The share of diffuse light inside the coat that it reflects back in: 1 - 2 \int T_in(mu) mu
  // dmu, with T_in the transmittance from inside (Mitsuba's Fdr).
  float internalDiffuseReflectance() const { return internalDiffuseReflectance_; }

  static constexpr int kResolution = 64;  // table entries over mu in [0, 1]

 private:
  static float lookup(const std::vector<float>& table, float mu);
  std::vector<float> outside_;
  float internalDiffuseReflectance_ = 0;
};

// The coating for these parameters, shared by every description alive that asked for the same
// ones (a scene's many plastics of one kind tabulate it once); freed with the last of them.
std::shared_ptr<const CoatingTransmittance> sharedCoatingTransmittance(MicrofacetDistribution dist,
                                                                       float alpha, float eta);

class Bsdf {
 public:
  // A CoatedDiffuse description must carry its coating, which this Bsdf then shares. A copy of a
  // Bsdf is a view: it points at the coating without sharing it, so it must not outlive the Bsdf
  // it was copied from (Scene::bsdfAt copies one per shading point, from Bsdfs the Scene keeps;
  // a shared count changed by every thread at once would be a contended cache line). Moves
  // move the share.
  explicit Bsdf(const BsdfDescription& desc);
  Bsdf(const Bsdf& other);
  Bsdf& operator=(const Bsdf& other);
  Bsdf(Bsdf&&) noexcept = default;
  Bsdf& operator=(Bsdf&&) noexcept = default;
  ~Bsdf() = default;

  // f(wo, wi) without the cosine; zero for delta lobes.
  Spectrum eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const;
  // Solid-angle density of sample() returning wi given wo; zero for delta lobes.
  float pdf(const Vec3f& wo, const Vec3f& wi) const;
  // u: three uniform numbers (lobe choice, then 2D direction). False when no direction results.
  bool sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const;

  // Has only Dirac lobes (the smooth dielectric and conductor).
  bool isDelta() const;

  // Dirac lobes, for the path-space mutations, which evaluate paths through specular vertices
  // by the coefficients of their delta functions (Veach 1997, 8.3.2).
  // The direction the reflection (or refraction) lobe takes wo to; false where it does not
  // exist (refraction beyond the critical angle) or the BSDF has no Dirac lobes.
  bool specularDirection(const Vec3f& wo, bool reflection, Vec3f* wi) const;
  // The Dirac lobe that joins wo and wi, told by their sides (reflection when on the same side):
  // which lobe, the probability with which sample() chooses it, and its value f |cos wi| / delta
  // for `mode` (the Fresnel term, times the radiance compression of refraction), both from wo.
  // False when there is no such lobe (refraction beyond the critical angle, no Dirac lobes).
  bool specularLobe(const Vec3f& wo, const Vec3f& wi, TransportMode mode, bool* reflection,
                    float* probability, Spectrum* value) const;
  // For directions a and b that a Dirac lobe joins, the ratio of solid angles d(omega_a) /
  // d(omega_b) of the lobe's map from b to a: one for reflection, (eta_b^2 |cos b|) /
  // (eta_a^2 |cos a|) for refraction (etendue is kept: eta^2 cos d(omega) is the same on both
  // sides). It converts a delta function in one direction into one in the other.
  float diracJacobian(const Vec3f& a, const Vec3f& b) const;
  bool isBlack() const;  // reflects nothing at all (e.g. the black diffuse of a light)
  // The description, less its id and its coating (see the constructor).
  const BsdfDescription& description() const { return desc_; }
  // The diffuse reflectance at one shading point, where a texture gives it (Scene::bsdfAt).
  void setReflectance(const Spectrum& reflectance);

 private:
  Spectrum conductorFresnel(float cosThetaI) const;  // times specularReflectance
  Spectrum roughDielectricEval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const;
  float roughDielectricPdf(const Vec3f& wo, const Vec3f& wi) const;
  bool roughDielectricSample(const Vec3f& wo, const float u[3], TransportMode mode,
                             BsdfSample* out) const;
  // Plastic: the probability of sampling the diffuse lobe (by the lobes' luminance), and the
  // glossy lobe's value.
  float plasticDiffuseProbability() const;
  Spectrum plasticGlossy(const Vec3f& wo, const Vec3f& wi) const;
  // CoatedDiffuse: the base's value, and the probability of sampling the glossy lobe from wo.
  Spectrum coatedBase(const Vec3f& wo, const Vec3f& wi) const;
  float coatedGlossyProbability(const Vec3f& wo) const;
  // Plastic and CoatedDiffuse: the probability that sample() takes the diffuse lobe at wo.
  float diffuseProbability(const Vec3f& wo) const;

  BsdfDescription desc_;
  BsdfDescription::Type type_;
  const CoatingTransmittance* coating_ = nullptr;
  std::shared_ptr<const CoatingTransmittance> coatingShare_;  // empty in copies
};

// Fresnel reflectance of a dielectric interface for cos(theta_i) (sign: which side) and the
// relative index eta = n_inside / n_outside; sets *cosThetaT to the refracted cosine (>= 0).
float fresnelDielectric(float cosThetaI, float eta, float* cosThetaT);
// Fresnel reflectance of a conductor with complex index eta + i k (relative to the exterior).
Spectrum fresnelConductor(float cosThetaI, const Spectrum& eta, const Spectrum& k);

}  // namespace farm
