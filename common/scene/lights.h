#pragma once
// The scene's lights behind one interface: emitting shapes (area lights), point and spot lights
// and the environment, each a Light. Lights owns picking one (in proportion to power), the
// triangle of a mesh light a point lies on, what each emits and the densities with which light
// subpaths start on them and leave them: every estimator and mutation takes its light densities
// from here, so that its MIS weights agree with the sampling they weigh (pbrt-v4's LightSampler
// and Light, Tungsten's Primitive emission, in one owner). Scene builds it and places points on
// the shapes (Scene::sampleLightPoint); read-only after that.
#include <cstdint>
#include <memory>
#include <vector>

#include "common/math/vec.h"
#include "common/scene/environment_light.h"
#include "common/scene/point_light.h"

namespace farm {

// One light: an emitting shape, sampled uniformly by area, emitting on its normal's side (or on
// both); a point light (point >= 0: Lights::pointLight()); or, with neither, the environment
// (Lights::environment()), whose path vertices lie at infinity.
struct Light {
  int shape = -1;
  int point = -1;  // index into the point lights
  Spectrum radiance;
  float area = 0;
  float power = 0;  // luminance of radiance * area * pi (twice for two sides): selection weight
  bool twoSided = false;  // an area light that emits on both sides of its surface
  bool isEnvironment() const { return shape < 0 && point < 0; }
  bool isPoint() const { return point >= 0; }
};

class Lights {
 public:
  // Building, in Scene's constructor: then finish() once.
  // An emitting shape; triangleAreaCdf is its triangles' running area (empty for a sphere).
  int addShape(int shape, const Spectrum& radiance, double area, bool twoSided,
               std::vector<double> triangleAreaCdf);
  // The environment (none when it emits nothing), its selection weight its flux through the disk
  // of the scene's bounding sphere (radius extent) that its light subpaths leave by.
  void addEnvironment(std::unique_ptr<EnvironmentLight> environment, const Spectrum& scale,
                      float extent);
  void addPoint(const PointLight& point, const Spectrum& intensity);  // none if it emits nothing
  // The scene's bounding sphere, and the selection CDF.
  void finish(const Vec3f& centre, float extent);

  size_t size() const { return lights_.size(); }
  bool empty() const { return lights_.empty(); }
  const Light& operator[](int light) const { return lights_[size_t(light)]; }
  std::vector<Light>::const_iterator begin() const { return lights_.begin(); }
  std::vector<Light>::const_iterator end() const { return lights_.end(); }

  // Chooses a light in proportion to power; *pdf is its discrete probability.
  int pick(float u, float* pdf) const;
  float pickPdf(int light) const;
  // The probability with which pick() picks a light, as its CDF makes it.
  double pickProbability(int light) const;
  // The density with which a light subpath starts where it does: pick()'s probability of the
  // light times that of the start on it, the area density 1 / area on an area light, the
  // coefficient 1 of a point light's delta, and the solid-angle density of the direction
  // `towardsEnvironment` for the environment. Every estimator's MIS weights take it from here
  // (pt's weight for a light it hits, BDPT's and the path-space chains' reverse densities, the
  // chains' seen emission), so that they agree with the sampling they weigh. In double: the
  // float quotients and products the estimators computed before are this, rounded.
  double startDensity(int light, const Vec3f& towardsEnvironment = Vec3f(0.0f)) const;

  // The triangle of a mesh light that a uniform number picks, by area (0 for a sphere).
  uint32_t pickTriangle(int light, float u) const;
  // The probability with which pickTriangle picks triangle t, as its CDF makes it: what the area
  // density 1 / area assumes to be area(t) / area. The CDFs are summed in double so that this
  // holds for 10^5 triangles of very different sizes (in float, a triangle smaller than a
  // rounding step of the running sum would get probability 0 or twice its share).
  double trianglePickProbability(int light, uint32_t t) const;

  // The environment, or null; environmentLight() is its index (or -1).
  const EnvironmentLight* environment() const { return environment_.get(); }
  int environmentLight() const { return environmentLight_; }
  // Light subpaths leave the environment through a disk of the bounding sphere's radius facing
  // their direction, uniformly: this is the disk's area density (pbrt-v3's infinite light emits
  // the same way: a density of directions times one of positions on such a disk).
  float environmentDiskDensity() const { return 1 / (kPi * extent_ * extent_); }
  // The point of that disk for two uniform numbers, the disk facing unit direction w (towards
  // the environment) from outside the scene.
  Vec3f environmentDiskPoint(const Vec3f& w, const Vec2f& u) const;
  const PointLight& pointLight(int light) const { return points_[size_t(lights_[light].point)]; }
  const std::vector<PointLight>& pointLights() const { return points_; }

  // Radiance leaving light `light` in direction w at a point of normal n; for the environment,
  // the radiance travelling in direction w, and for a point light its intensity in direction w
  // (n is not used for either).
  Spectrum emitted(int light, const Vec3f& n, const Vec3f& w) const {
    const Light& l = lights_[size_t(light)];
    if (light == environmentLight_) return environment_->radiance(-w);
    if (l.isPoint()) return pointLight(light).intensity(w);
    const float c = dot(n, w);
    return c > 0 || (l.twoSided && c < 0) ? l.radiance : Spectrum(0.0f);
  }
  // The solid-angle density with which an area light's subpaths leave it in direction w at a
  // point of normal n: cosine-weighted about n, on a side picked with probability 1/2 when the
  // light has two.
  float emissionPdf(int light, const Vec3f& n, const Vec3f& w) const {
    const float c = dot(n, w);
    return lights_[size_t(light)].twoSided ? 0.5f * kInvPi * std::fabs(c)
                                           : (c > 0 ? c * kInvPi : 0.0f);
  }
  // A direction of an area light's emission, in its local frame (z along n), with emissionPdf's
  // density: cosine-weighted about z, or about -z for the back side, which a two-sided light
  // picks with the first number (rescaled, so that stratified numbers stay stratified).
  Vec3f sampleEmission(int light, Vec2f u) const;

 private:
  std::vector<Light> lights_;
  std::vector<double> cdf_;                       // running power, per light
  std::vector<std::vector<double>> triangleCdf_;  // per light: its mesh's running area
  std::unique_ptr<EnvironmentLight> environment_;
  std::vector<PointLight> points_;
  int environmentLight_ = -1;
  Vec3f centre_{0.0f};
  float extent_ = 1;
};

}  // namespace farm
