#pragma once
// Maps from the unit square to the domains the transport samples, with their densities.
#include <cmath>

#include "common/math/vec.h"

namespace farm {

// Shirley-Chiu concentric map: low distortion, keeps stratification (and small steps small).
inline Vec2f squareToConcentricDisk(const Vec2f& u) {
  float a = 2 * u.x - 1, b = 2 * u.y - 1;
  if (a == 0 && b == 0) return {0, 0};
  float r, phi;
  if (std::fabs(a) > std::fabs(b)) {
    r = a;
    phi = (kPi / 4) * (b / a);
  } else {
    r = b;
    phi = (kPi / 2) - (kPi / 4) * (a / b);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

// Cosine-weighted hemisphere around +z (Malley's method); pdf = cos(theta) / pi.
inline Vec3f squareToCosineHemisphere(const Vec2f& u) {
  Vec2f d = squareToConcentricDisk(u);
  float z = std::sqrt(std::max(0.0f, 1 - d.x * d.x - d.y * d.y));
  return {d.x, d.y, z};
}
inline float cosineHemispherePdf(float cosTheta) {
  return cosTheta > 0 ? cosTheta * kInvPi : 0;
}

inline Vec3f squareToUniformSphere(const Vec2f& u) {
  float z = 1 - 2 * u.x;
  float r = std::sqrt(std::max(0.0f, 1 - z * z));
  float phi = 2 * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// Uniform barycentrics on a triangle (the square-root parameterization).
inline Vec2f squareToTriangle(const Vec2f& u) {
  float su = std::sqrt(u.x);
  return {1 - su, u.y * su};
}

}  // namespace farm
