#pragma once
// The optics of a smooth interface that every BSDF model shares: the Fresnel equations, and the
// directions they weigh (the mirror law and Snell's law), in the local shading frame (z = normal)
// or about a microfacet normal m.
#include "common/math/vec.h"

namespace farm {

// Fresnel reflectance of a dielectric interface for cos(theta_i) (sign: which side) and the
// relative index eta = n_inside / n_outside; sets *cosThetaT to the refracted cosine (>= 0).
float fresnelDielectric(float cosThetaI, float eta, float* cosThetaT);
// Fresnel reflectance of a conductor with complex index eta + i k (relative to the exterior).
Spectrum fresnelConductor(float cosThetaI, const Spectrum& eta, const Spectrum& k);

// The Fresnel reflectance of a refraction whose two cosines are known (to the facet, each on its
// own side, with that side's index): symmetric in the two sides, so a refraction and its
// reverse get the same value, and well-conditioned near the critical angle, where recovering
// the refracted cosine from the incident one loses the digits that 1 - F is made of.
float fresnelOfRefraction(float cosA, float etaA, float cosB, float etaB);

// wo mirrored about the unit normal m.
inline Vec3f reflect(const Vec3f& wo, const Vec3f& m) {
  return 2 * dot(wo, m) * m - wo;
}

// Snell's law about the local normal (0, 0, 1): wo refracted into the other side, with etaTI
// the index ratio transmitted side / incident side and cosT the refracted cosine (>= 0).
Vec3f refracted(const Vec3f& wo, float etaTI, float cosT);

// Snell's law about a microfacet normal m (Walter et al. 2007, eq. 40): wo refracted through
// the facet, with etaTI = eta_t / eta_i and cosT the refracted cosine to m (>= 0).
Vec3f refractedAbout(const Vec3f& wo, const Vec3f& m, float etaTI, float cosT);

}  // namespace farm
