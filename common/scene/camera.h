#pragma once
// Mitsuba's perspective sensor: a pinhole, or a thin lens (Mitsuba's thinlens, pbrt's perspective
// camera with a lens radius). Film coordinates are in pixels: x to the right, y down,
// [0, width) x [0, height). Camera space looks down +z with +x towards the image's left.
//
// Importance is normalized so that pixel j of the image is I_j = A_px * Int h_j(p(w)) We(w) L(w)
// dw, with A_px = width*height, h_j the pixel's filter (integrating to one over the film, in
// pixel units), and We(w) = 1 / (A_plane cos^3 theta), A_plane the image plane's area at unit
// distance. Sampling a film point uniformly gives directions with density exactly We.
//
// A thin lens adds a point on the lens disk (area A_lens), sampled uniformly: a ray leaves it
// towards the point of the focus plane (at the focus distance along the view direction) that
// the pinhole sees through the film point. From a fixed lens point, the film point is still the
// pinhole projection of where the ray meets the focus plane, and its direction density is the
// same 1 / (A_plane cos^3 theta): the plane at distance f is covered uniformly, and converting
// its area density 1 / (A_plane f^2) to solid angle at the lens point gives that expression
// (pbrt's We = 1 / (A_lens A_plane cos^4) over the lens's area measure with its cosine, times
// the lens point's density A_lens, is the same). So every estimator treats the lens point as
// it treats the pinhole, with the lens point in its place; the lens point's own density
// 1 / A_lens is common to every strategy that ends on the camera, and MIS ignores it.
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

  bool hasLens() const { return lensRadius_ > 0; }
  // The point of the lens for two uniform numbers (the position for a pinhole).
  Vec3f lensPoint(const Vec2f& uLens) const;
  // The primary ray through film point `film` (pixels) from `lensPoint`; its direction density
  // is We(d).
  Ray generateRay(const Vec2f& film, const Vec3f& lensPoint) const;
  // The pinhole's ray (from position()).
  Ray generateRay(const Vec2f& film) const { return generateRay(film, position_); }
  // Whether p is a point of the lens (the position for a pinhole), to rounding: what a path's
  // camera vertex must be.
  bool onLens(const Vec3f& p) const;
  // Where the ray from lens point `lensPoint` in direction d (world, unit) comes from on the
  // film; false when outside.
  bool project(const Vec3f& lensPoint, const Vec3f& d, Vec2f* film) const;
  // We(d) per unit solid angle at `lensPoint`, as above; zero outside the frustum. Equal to the
  // pdf of d.
  float importance(const Vec3f& lensPoint, const Vec3f& d) const;

 private:
  Vec3f position_, forward_, right_, up_;  // right_ = world direction of the image's +x
  float tanHalfX_, tanHalfY_;              // image plane half extents at unit distance
  float planeArea_;
  int width_, height_;
  float lensRadius_ = 0, focusDistance_ = 1;
};

}  // namespace farm
