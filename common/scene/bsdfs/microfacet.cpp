#include "common/scene/bsdfs/microfacet.h"

#include <algorithm>
#include <cmath>

namespace farm {

namespace {

// Samples a normal with density D(m) cos(theta_m).
Vec3f sampleByDensity(MicrofacetDistribution dist, float alpha, float u1, float u2) {
  float tan2;
  if (dist == MicrofacetDistribution::Beckmann) {
    tan2 = -alpha * alpha * std::log1p(-u1);
  } else {
    tan2 = alpha * alpha * u1 / (1 - u1);
  }
  float cosTheta = 1 / std::sqrt(1 + tan2);
  float sinTheta = std::sqrt(tan2) * cosTheta;  // not sqrt(1 - cos^2): see D()
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

}  // namespace

float Microfacet::D(const Vec3f& m) const {
  float c = m.z;
  if (c <= 0) return 0;
  float c2 = c * c;
  // sin^2 from the tangential components: 1 - cos^2 cancels catastrophically in float for the
  // narrow lobes (alpha down to 1e-4) where theta_m is tiny.
  float tan2 = (m.x * m.x + m.y * m.y) / c2;
  float a2 = alpha * alpha;
  if (distribution == MicrofacetDistribution::Beckmann) {
    // eq. 25
    return std::exp(-tan2 / a2) / (kPi * a2 * c2 * c2);
  }
  // GGX, eq. 33
  float root = a2 + tan2;
  return a2 / (kPi * c2 * c2 * root * root);
}

float Microfacet::G1(const Vec3f& v, const Vec3f& m) const {
  if (dot(v, m) * v.z <= 0) return 0;
  float sin2 = v.x * v.x + v.y * v.y;
  if (sin2 == 0) return 1;
  float tanTheta = std::sqrt(sin2) / std::fabs(v.z);
  if (distribution == MicrofacetDistribution::Beckmann) {
    float a = 1 / (alpha * tanTheta);
    if (a >= 1.6f) return 1;
    return (3.535f * a + 2.181f * a * a) / (1 + 2.276f * a + 2.577f * a * a);
  }
  float at = alpha * tanTheta;
  return 2 / (1 + std::sqrt(1 + at * at));
}

Vec3f Microfacet::sample(const Vec3f& wo, float u1, float u2) const {
  if (distribution == MicrofacetDistribution::Beckmann)
    return sampleByDensity(distribution, alpha, u1, u2);
  return sampleVisibleGgx(alpha, wo.z > 0 ? wo : -wo, u1, u2);
}

float Microfacet::pdf(const Vec3f& wo, const Vec3f& m) const {
  const float d = D(m);
  if (distribution == MicrofacetDistribution::Beckmann) return d * m.z;
  return G1(wo, m) * std::fabs(dot(wo, m)) * d / std::fabs(wo.z);
}

float Microfacet::weight(const Vec3f& wo, const Vec3f& wi, const Vec3f& m) const {
  if (distribution == MicrofacetDistribution::GGX) return G1(wi, m);
  return G1(wo, m) * G1(wi, m) * std::fabs(dot(wo, m)) / (std::fabs(wo.z) * m.z);
}

bool reflectionHalfVector(const Vec3f& wo, const Vec3f& wi, Vec3f* h) {
  const Vec3f sum = wo + wi;
  const float l = length(sum);
  if (!(l > 0)) return false;
  *h = sum.z < 0 ? -sum / l : sum / l;
  return true;
}

Vec3f transmissionHalfVector(const Vec3f& wo, const Vec3f& wi, float etaO, float etaI) {
  Vec3f h = -(etaO * wo + etaI * wi);
  const float l = length(h);
  if (!(l > 0)) return Vec3f(0.0f);
  h = h / l;
  return h.z < 0 ? -h : h;
}

}  // namespace farm
