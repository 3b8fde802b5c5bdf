#pragma once
// A point light (PointLightDescription): its intensity by direction and the directions its
// light subpaths leave in, uniform over the sphere, or over a spot's cone, which holds all of
// its emission.
#include "common/math/vec.h"
#include "common/scene/scene_description.h"

namespace farm {

class PointLight {
 public:
  explicit PointLight(const PointLightDescription& description);

  const Vec3f& position() const { return d_.position; }
  // Radiant intensity emitted in unit direction w.
  Spectrum intensity(const Vec3f& w) const;
  // A direction of emission from two uniform numbers, and its solid-angle density.
  Vec3f sampleDirection(const Vec2f& u, float* pdf) const;
  float directionPdf(const Vec3f& w) const;
  // Luminance of the emitted power (over the sphere; a spot's approximated as pbrt does, by
  // the cone up to the middle of its falloff): the light selection weight.
  double power() const;

 private:
  float falloff(float cosTheta) const;
  PointLightDescription d_;
  Frame frame_;  // z along a spot's direction
};

}  // namespace farm
