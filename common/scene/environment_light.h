#pragma once
// The environment at infinity (EnvironmentDescription): radiance by direction, and directions
// sampled in proportion to the radiance's luminance, so that a small bright sun in a large dim
// sky is found by next-event estimation and by light subpaths. A map (lat-long or equal-area) is
// sampled as a piecewise-constant density over its texels, each weighted by its luminance times
// its solid angle, and its radiance is looked up at the nearest texel: the density is then
// positive exactly where the radiance is, which unbiasedness needs (a bilinear lookup would glow
// into black texels that the density never samples).
#include <vector>

#include "common/math/transform.h"
#include "common/math/vec.h"
#include "common/scene/scene_description.h"

namespace farm {

class EnvironmentLight {
 public:
  explicit EnvironmentLight(const EnvironmentDescription& description);

  // Radiance arriving from world direction w (unit, pointing away from the scene).
  Spectrum radiance(const Vec3f& w) const;
  // A direction from two uniform numbers and its solid-angle density; *pdf = 0 when none.
  Vec3f sample(const Vec2f& u, float* pdf) const;
  // The solid-angle density with which sample() returns w.
  float pdf(const Vec3f& w) const;
  // The integral of the radiance's luminance over the sphere of directions.
  double luminanceIntegral() const { return luminanceIntegral_; }

 private:
  // Texel (x, y) of the map as it is lit: scale times the texel, negatives and NaN as zero.
  Spectrum texel(int x, int y) const;
  // The texel a local direction falls in; returns the map's area (in [0, 1]^2) per unit solid
  // angle there (0 at a lat-long map's poles).
  double texelOf(const Vec3f& local, int* x, int* y) const;

  EnvironmentDescription description_;
  Matrix4 toLocal_;
  int width_ = 0, height_ = 0;    // 0: a constant environment
  std::vector<double> rowCdf_;    // height_ entries: the marginal over rows, unnormalized
  std::vector<double> texelCdf_;  // width_ per row: the conditional within each row
  double luminanceIntegral_ = 0;
};

}  // namespace farm
