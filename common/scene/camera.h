#pragma once
// Mitsuba's perspective pinhole sensor. Film coordinates are in pixels: x to the right, y down,
// [0, width) x [0, height). Camera space looks down +z with +x towards the image's left.
//
// Importance is normalized so that pixel j of the image is I_j = A_px * Int h_j(p(w)) We(w) L(w)
// dw, with A_px = width*height, h_j the pixel's filter (integrating to one over the film, in
// pixel units), and We(w) = 1 / (A_plane cos^3 theta), A_plane the image plane's area at unit
// distance. Sampling a film point uniformly gives directions with density exactly We.
#include "common/math/vec.h"
#include "common/scene/scene_description.h"

namespace farm {

struct Ray {
  Vec3f o, d;
  float tMax = kInfinity;
};

class Camera {
 public:
  explicit Camera(const CameraDescription& desc);

  int width() const { return width_; }
  int height() const { return height_; }
  float pixelCount() const { return float(width_) * float(height_); }
  const Vec3f& position() const { return position_; }
  const Vec3f& forward() const { return forward_; }

  // The primary ray through film point `film` (pixels); its direction density is We(d).
  Ray generateRay(const Vec2f& film) const;
  // Where direction d (world, unit, from the camera) meets the film; false when outside.
  bool project(const Vec3f& d, Vec2f* film) const;
  // We(d) per unit solid angle, as above; zero outside the frustum. Equal to the pdf of d.
  float importance(const Vec3f& d) const;

 private:
  Vec3f position_, forward_, right_, up_;  // right_ = world direction of the image's +x
  float tanHalfX_, tanHalfY_;              // image plane half extents at unit distance
  float planeArea_;
  int width_, height_;
};

}  // namespace farm
