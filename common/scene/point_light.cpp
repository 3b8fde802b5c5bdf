#include "common/scene/point_light.h"

#include <algorithm>
#include <cmath>

#include "common/sampling/warp.h"

namespace farm {

PointLight::PointLight(const PointLightDescription& description)
    : d_(description), frame_(description.spot ? description.direction : Vec3f(0, 0, 1)) {}

float PointLight::falloff(float cosTheta) const {
  if (!d_.spot) return 1;
  if (cosTheta <= d_.cosTotalWidth) return 0;
  if (cosTheta >= d_.cosFalloffStart) return 1;
  const float t = (cosTheta - d_.cosTotalWidth) / (d_.cosFalloffStart - d_.cosTotalWidth);
  switch (d_.falloff) {
    case PointLightDescription::Falloff::PbrtV3Quartic:
      return (t * t) * (t * t);
    case PointLightDescription::Falloff::PbrtV4Smoothstep:
      return t * t * (3 - 2 * t);
    case PointLightDescription::Falloff::MitsubaLinearAngle: {
      const float cutoff = std::acos(d_.cosTotalWidth), beam = std::acos(d_.cosFalloffStart);
      return std::clamp((cutoff - std::acos(std::clamp(cosTheta, -1.0f, 1.0f))) / (cutoff - beam),
                        0.0f, 1.0f);
    }
  }
  return 1;
}

Spectrum PointLight::intensity(const Vec3f& w) const {
  return d_.intensity * falloff(dot(w, frame_.n));
}

Vec3f PointLight::sampleDirection(const Vec2f& u, float* pdf) const {
  if (!d_.spot) {
    *pdf = 1 / (4 * kPi);
    return squareToUniformSphere(u);
  }
  // Uniform over the cone cos(theta) > cosTotalWidth.
  const float cosTheta = 1 - u.x * (1 - d_.cosTotalWidth);
  const float sinTheta = std::sqrt(std::max(0.0f, 1 - cosTheta * cosTheta));
  const float phi = 2 * kPi * u.y;
  *pdf = 1 / (2 * kPi * (1 - d_.cosTotalWidth));
  return frame_.toWorld(Vec3f(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta));
}

float PointLight::directionPdf(const Vec3f& w) const {
  if (!d_.spot) return 1 / (4 * kPi);
  return dot(w, frame_.n) > d_.cosTotalWidth ? 1 / (2 * kPi * (1 - d_.cosTotalWidth)) : 0.0f;
}

double PointLight::power() const {
  const double lum = luminance(d_.intensity);
  if (!d_.spot) return 4 * M_PI * lum;
  return 2 * M_PI * lum * (1 - 0.5 * (double(d_.cosFalloffStart) + d_.cosTotalWidth));
}

}  // namespace farm
