#include "common/scene/environment_light.h"

#include <algorithm>
#include <cmath>

#include "common/sampling/warp.h"

namespace farm {

namespace {

constexpr double kPiD = 3.14159265358979323846;

// The bin of a CDF (unnormalized, increasing) that u * total falls in, and u rescaled to [0, 1)
// within that bin (so that stratified numbers stay stratified).
int pickBin(const double* cdf, int n, double u, double* remapped) {
  const double target = u * cdf[n - 1];
  int i = int(std::upper_bound(cdf, cdf + n, target) - cdf);
  i = std::min(i, n - 1);
  while (i > 0 && cdf[i] == cdf[i - 1]) --i;  // never a bin of zero weight
  const double lo = i > 0 ? cdf[i - 1] : 0.0, width = cdf[i] - lo;
  *remapped = width > 0 ? std::clamp((target - lo) / width, 0.0, 1.0 - 1e-9) : 0.5;
  return i;
}

}  // namespace

EnvironmentLight::EnvironmentLight(const EnvironmentDescription& description)
    : description_(description), toLocal_(description.toWorld.inverse()) {
  const TextureImage* image = description_.image.get();
  if (!image || image->width < 1 || image->height < 1) {
    luminanceIntegral_ = 4 * kPiD * double(luminance(description_.scale));
    return;
  }
  width_ = image->width;
  height_ = image->height;
  rowCdf_.resize(size_t(height_));
  texelCdf_.resize(size_t(width_) * size_t(height_));
  double rows = 0;
  const bool equalArea = description_.mapping == EnvironmentDescription::Mapping::EqualArea;
  for (int y = 0; y < height_; ++y) {
    // Texel weights: luminance times the texel's solid angle; a lat-long row's is
    // (2 pi / W)(cos(theta0) - cos(theta1)), an equal-area map's 4 pi / (W H) everywhere.
    const double theta0 = kPiD * y / height_, theta1 = kPiD * (y + 1) / height_;
    const double solidAngle = equalArea
                                  ? 4 * kPiD / (double(width_) * height_)
                                  : (2 * kPiD / width_) * (std::cos(theta0) - std::cos(theta1));
    double row = 0;
    double* cdf = &texelCdf_[size_t(y) * size_t(width_)];
    for (int x = 0; x < width_; ++x) {
      const double lum = double(luminance(texel(x, y)));
      row += lum * solidAngle;
      cdf[x] = row;
    }
    rows += row;
    rowCdf_[size_t(y)] = rows;
  }
  luminanceIntegral_ = rows;
}

Spectrum EnvironmentLight::texel(int x, int y) const {
  Spectrum t = description_.image->texel(x, y) * description_.scale;
  for (int c = 0; c < 3; ++c) {
    if (!(t[c] > 0) || !std::isfinite(t[c])) t[c] = 0;
  }
  return t;
}

double EnvironmentLight::texelOf(const Vec3f& local, int* x, int* y) const {
  double u, v, areaPerSolidAngle;
  if (description_.mapping == EnvironmentDescription::Mapping::EqualArea) {
    const Vec2f p = equalAreaSphereToSquare(local);
    u = p.x;
    v = p.y;
    areaPerSolidAngle = 1 / (4 * kPiD);
  } else {
    // du dv = dphi dtheta / (2 pi^2), and d(omega) = sin(theta) dphi dtheta.
    const double z = std::clamp(double(local.z), -1.0, 1.0);
    double phi = std::atan2(double(local.y), double(local.x));
    if (phi < 0) phi += 2 * kPiD;
    u = phi / (2 * kPiD);
    v = std::acos(z) / kPiD;
    const double sinTheta = std::sqrt(std::max(0.0, 1 - z * z));
    areaPerSolidAngle = sinTheta > 0 ? 1 / (2 * kPiD * kPiD * sinTheta) : 0;
  }
  *x = std::clamp(int(u * width_), 0, width_ - 1);
  *y = std::clamp(int(v * height_), 0, height_ - 1);
  return areaPerSolidAngle;
}

Spectrum EnvironmentLight::radiance(const Vec3f& w) const {
  if (width_ == 0) return description_.scale;
  int x, y;
  texelOf(normalize(toLocal_.applyVector(w)), &x, &y);
  return texel(x, y);
}

Vec3f EnvironmentLight::sample(const Vec2f& u, float* pdf) const {
  *pdf = 0;
  if (!(luminanceIntegral_ > 0)) return Vec3f(0.0f);
  if (width_ == 0) {
    *pdf = 1 / (4 * kPi);
    return normalize(description_.toWorld.applyVector(squareToUniformSphere(u)));
  }
  double uRow, uColumn;
  const int y = pickBin(rowCdf_.data(), height_, double(u.y), &uRow);
  const int x = pickBin(&texelCdf_[size_t(y) * size_t(width_)], width_, double(u.x), &uColumn);
  // A point uniform within the texel's rectangle of the map.
  const double u01 = (x + uColumn) / width_, v01 = (y + uRow) / height_;
  Vec3f local;
  if (description_.mapping == EnvironmentDescription::Mapping::EqualArea) {
    local = equalAreaSquareToSphere(Vec2f(float(u01), float(v01)));
  } else {
    const double phi = 2 * kPiD * u01, theta = kPiD * v01;
    const double sinTheta = std::sin(theta);
    if (!(sinTheta > 0)) return Vec3f(0.0f);
    local = Vec3f(float(sinTheta * std::cos(phi)), float(sinTheta * std::sin(phi)),
                  float(std::cos(theta)));
  }
  const Vec3f w = normalize(description_.toWorld.applyVector(local));
  *pdf = this->pdf(w);  // from the direction, as every other strategy will compute it
  return w;
}

float EnvironmentLight::pdf(const Vec3f& w) const {
  if (!(luminanceIntegral_ > 0)) return 0;
  if (width_ == 0) return 1 / (4 * kPi);
  int x, y;
  const double areaPerSolidAngle = texelOf(normalize(toLocal_.applyVector(w)), &x, &y);
  if (!(areaPerSolidAngle > 0)) return 0;
  const double* cdf = &texelCdf_[size_t(y) * size_t(width_)];
  const double weight = cdf[x] - (x > 0 ? cdf[x - 1] : 0.0);
  // The texel's probability spread uniformly over its rectangle of the map, of area 1 / (W H).
  const double probability = weight / luminanceIntegral_;
  return float(probability * width_ * height_ * areaPerSolidAngle);
}

}  // namespace farm
