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
  for (int y = 0; y < height_; ++y) {
    // Texel weights: luminance times the texel's solid angle, whose theta-dependence is
    // cos(theta0) - cos(theta1), proportional to sin(theta) at the row's centre up to O(1/H^2).
    const double theta0 = kPiD * y / height_, theta1 = kPiD * (y + 1) / height_;
    const double solidAngle = (2 * kPiD / width_) * (std::cos(theta0) - std::cos(theta1));
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

void EnvironmentLight::texelOf(const Vec3f& local, int* x, int* y, float* sinTheta) const {
  const double z = std::clamp(double(local.z), -1.0, 1.0);
  double phi = std::atan2(double(local.y), double(local.x));
  if (phi < 0) phi += 2 * kPiD;
  const double theta = std::acos(z);
  *x = std::clamp(int(phi / (2 * kPiD) * width_), 0, width_ - 1);
  *y = std::clamp(int(theta / kPiD * height_), 0, height_ - 1);
  *sinTheta = float(std::sqrt(std::max(0.0, 1 - z * z)));
}

Spectrum EnvironmentLight::radiance(const Vec3f& w) const {
  if (width_ == 0) return description_.scale;
  int x, y;
  float sinTheta;
  texelOf(normalize(toLocal_.applyVector(w)), &x, &y, &sinTheta);
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
  const double phi = 2 * kPiD * (x + uColumn) / width_;
  const double theta = kPiD * (y + uRow) / height_;
  const double sinTheta = std::sin(theta);
  if (!(sinTheta > 0)) return Vec3f(0.0f);
  const Vec3f local(float(sinTheta * std::cos(phi)), float(sinTheta * std::sin(phi)),
                    float(std::cos(theta)));
  const Vec3f w = normalize(description_.toWorld.applyVector(local));
  *pdf = this->pdf(w);  // from the direction, as every other strategy will compute it
  return w;
}

float EnvironmentLight::pdf(const Vec3f& w) const {
  if (!(luminanceIntegral_ > 0)) return 0;
  if (width_ == 0) return 1 / (4 * kPi);
  int x, y;
  float sinTheta;
  texelOf(normalize(toLocal_.applyVector(w)), &x, &y, &sinTheta);
  if (!(sinTheta > 0)) return 0;
  const double* cdf = &texelCdf_[size_t(y) * size_t(width_)];
  const double weight = cdf[x] - (x > 0 ? cdf[x - 1] : 0.0);
  // The texel's probability spread uniformly over its (phi, theta) rectangle of area
  // (2 pi / W)(pi / H), whose solid angle element is sin(theta) dphi dtheta.
  const double probability = weight / luminanceIntegral_;
  return float(probability * width_ * height_ / (2 * kPiD * kPiD * double(sinTheta)));
}

}  // namespace farm
