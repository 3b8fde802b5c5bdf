#pragma once
// Maps from the unit square to the domains the transport samples, with their densities.
#include <algorithm>
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

// Clarberg's equal-area octahedral map of the sphere (pbrt-v4's environment maps; Clarberg 2008,
// "Fast equal-area mapping of the (hemi)sphere using SIMD"): the square's inner diamond
// |u'| + |v'| <= 1 (u' = 2u - 1, v' = 2v - 1) is the upper hemisphere, z = 1 - r^2 with r the
// diamond's radius |u'| + |v'|, and the four corners fold onto the lower one; the angle about z
// runs linearly along each diamond edge. Every region of the square has the solid angle 4 pi
// times its area, so the density is 1 / (4 pi) per steradian for uniform u.
inline Vec3f equalAreaSquareToSphere(const Vec2f& u) {
  const double a = 2.0 * u.x - 1, b = 2.0 * u.y - 1;
  const double ap = std::fabs(a), bp = std::fabs(b);
  const double signedDistance = 1 - (ap + bp);  // > 0 inside the diamond
  const double r = 1 - std::fabs(signedDistance);
  const double phi = (r == 0 ? 1 : (bp - ap) / r + 1) * (3.14159265358979323846 / 4);
  const double z = std::copysign(1 - r * r, signedDistance);
  const double s = r * std::sqrt(std::max(0.0, 2 - r * r));
  return {float(std::copysign(std::cos(phi), a) * s), float(std::copysign(std::sin(phi), b) * s),
          float(z)};
}

// Its inverse: the point of the unit square whose image is the unit direction w.
inline Vec2f equalAreaSphereToSquare(const Vec3f& w) {
  const double x = std::fabs(double(w.x)), y = std::fabs(double(w.y));
  const double r = std::sqrt(std::max(0.0, 1 - std::fabs(double(w.z))));
  // The angle about z within the quadrant, as a fraction of a right angle.
  const double t = (x == 0 && y == 0) ? 0.5 : std::atan2(y, x) / (3.14159265358979323846 / 2);
  double bp = t * r, ap = r - bp;  // on the diamond of radius r
  if (w.z < 0) {                   // folded out to the corner: the radius counts from it
    const double ap0 = ap;
    ap = 1 - bp;
    bp = 1 - ap0;
  }
  const double a = std::copysign(ap, double(w.x)), b = std::copysign(bp, double(w.y));
  return {float((a + 1) / 2), float((b + 1) / 2)};
}

}  // namespace farm
