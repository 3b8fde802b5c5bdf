#include "common/scene/bsdfs/fresnel.h"

#include <algorithm>
#include <cmath>

namespace farm {

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

float fresnelOfRefraction(float cosA, float etaA, float cosB, float etaB) {
  cosA = std::fabs(cosA), cosB = std::fabs(cosB);
  const float rs = (etaA * cosA - etaB * cosB) / (etaA * cosA + etaB * cosB);
  const float rp = (etaB * cosA - etaA * cosB) / (etaB * cosA + etaA * cosB);
  return 0.5f * (rs * rs + rp * rp);
}

Vec3f refracted(const Vec3f& wo, float etaTI, float cosT) {
  float side = wo.z > 0 ? 1.0f : -1.0f;
  return normalize(-wo / etaTI + Vec3f(0, 0, side * (std::fabs(wo.z) / etaTI - cosT)));
}

Vec3f refractedAbout(const Vec3f& wo, const Vec3f& m, float etaTI, float cosT) {
  const float c = dot(wo, m);
  return normalize(-wo / etaTI + m * (c / etaTI - (c > 0 ? cosT : -cosT)));
}

}  // namespace farm
