#include "common/scene/lights.h"

#include <algorithm>

#include "common/sampling/warp.h"

namespace farm {

int Lights::addShape(int shape, const Spectrum& radiance, double area, bool twoSided,
                     std::vector<double> triangleAreaCdf) {
  Light light;
  light.shape = shape;
  light.radiance = radiance;
  light.area = float(area);
  light.twoSided = twoSided;
  light.power = float(double(luminance(radiance)) * area * kPi * (twoSided ? 2 : 1));
  lights_.push_back(light);
  triangleCdf_.push_back(std::move(triangleAreaCdf));
  return int(lights_.size()) - 1;
}

void Lights::addEnvironment(std::unique_ptr<EnvironmentLight> environment, const Spectrum& scale,
                            float extent) {
  if (!(environment->luminanceIntegral() > 0)) return;
  // Its flux through the disk that light subpaths leave by: the selection weight, in the units
  // of the area lights' (radiance * area * pi).
  Light light;
  light.shape = -1;
  light.radiance = scale;
  light.power = float(double(kPi) * extent * extent * environment->luminanceIntegral());
  environmentLight_ = int(lights_.size());
  lights_.push_back(light);
  triangleCdf_.emplace_back();
  environment_ = std::move(environment);
}

void Lights::addPoint(const PointLight& point, const Spectrum& intensity) {
  if (!(point.power() > 0)) return;  // emits nothing: sampling it would waste paths
  Light light;
  light.point = int(points_.size());
  light.radiance = intensity;
  light.power = float(point.power());
  lights_.push_back(light);
  triangleCdf_.emplace_back();
  points_.push_back(point);
}

void Lights::finish(const Vec3f& centre, float extent) {
  centre_ = centre;
  extent_ = extent;
  double total = 0;
  cdf_.clear();
  for (const Light& l : lights_) {
    total += double(l.power);
    cdf_.push_back(total);
  }
}

int Lights::pick(float u, float* pdf) const {
  if (lights_.empty()) return -1;
  const double total = cdf_.back();
  const double target = double(u) * total;
  int i = int(std::upper_bound(cdf_.begin(), cdf_.end(), target) - cdf_.begin());
  i = std::min(i, int(lights_.size()) - 1);
  *pdf = pickPdf(i);
  return i;
}

float Lights::pickPdf(int light) const {
  if (light < 0 || lights_.empty()) return 0;
  return float(double(lights_[size_t(light)].power) / cdf_.back());
}

double Lights::pickProbability(int light) const {
  if (light < 0 || light >= int(lights_.size())) return 0;
  return (cdf_[size_t(light)] - (light > 0 ? cdf_[size_t(light) - 1] : 0.0)) / cdf_.back();
}

double Lights::startDensity(int light, const Vec3f& towardsEnvironment) const {
  if (light < 0 || light >= int(lights_.size())) return 0;
  const double pick = double(pickPdf(light));
  if (light == environmentLight_) return pick * double(environment_->pdf(towardsEnvironment));
  if (lights_[size_t(light)].isPoint()) return pick;
  return pick / double(lights_[size_t(light)].area);
}

uint32_t Lights::pickTriangle(int light, float u) const {
  const std::vector<double>& cdf = triangleCdf_[size_t(light)];
  if (cdf.empty()) return 0;  // a sphere
  const double target = double(u) * cdf.back();
  size_t t = size_t(std::upper_bound(cdf.begin(), cdf.end(), target) - cdf.begin());
  return uint32_t(std::min(t, cdf.size() - 1));
}

double Lights::trianglePickProbability(int light, uint32_t t) const {
  if (light < 0 || light >= int(lights_.size()) || lights_[size_t(light)].shape < 0) return 0;
  const std::vector<double>& cdf = triangleCdf_[size_t(light)];
  if (cdf.empty()) return 1;  // a sphere: one primitive
  if (t >= cdf.size()) return 0;
  return (cdf[t] - (t > 0 ? cdf[t - 1] : 0.0)) / cdf.back();
}

Vec3f Lights::environmentDiskPoint(const Vec3f& w, const Vec2f& u) const {
  const Vec2f disk = squareToConcentricDisk(u);
  const Frame frame(w);
  return centre_ + (w + frame.s * disk.x + frame.t * disk.y) * extent_;
}

Vec3f Lights::sampleEmission(int light, Vec2f u) const {
  const bool twoSided = lights_[size_t(light)].twoSided;
  const bool back = twoSided && u.x >= 0.5f;
  if (twoSided) u.x = std::min(back ? 2 * u.x - 1 : 2 * u.x, 0x1.fffffep-1f);
  Vec3f local = squareToCosineHemisphere(u);
  if (back) local.z = -local.z;
  return local;
}

}  // namespace farm
