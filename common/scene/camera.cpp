#include "common/scene/camera.h"

#include <cmath>

#include "common/sampling/warp.h"

namespace farm {

Camera::Camera(const CameraDescription& desc)
    : width_(desc.width),
      height_(desc.height),
      lensRadius_(desc.lensRadius),
      focusDistance_(desc.focusDistance) {
  const Matrix4& m = desc.toWorld;
  position_ = m.applyPoint(Vec3f(0, 0, 0));
  forward_ = normalize(m.applyVector(Vec3f(0, 0, 1)));
  // Camera +x points to the image's left, so the image's right is camera -x.
  right_ = normalize(m.applyVector(Vec3f(-1, 0, 0)));
  up_ = normalize(m.applyVector(Vec3f(0, 1, 0)));

  float aspect = float(width_) / float(height_);
  float t = std::tan(desc.fovDegrees * kPi / 360.0f);
  switch (desc.fovAxis) {
    case FovAxis::X:
      tanHalfX_ = t, tanHalfY_ = t / aspect;
      break;
    case FovAxis::Y:
      tanHalfY_ = t, tanHalfX_ = t * aspect;
      break;
    case FovAxis::Smaller:
      if (aspect >= 1)
        tanHalfY_ = t, tanHalfX_ = t * aspect;
      else
        tanHalfX_ = t, tanHalfY_ = t / aspect;
      break;
    case FovAxis::Larger:
      if (aspect >= 1)
        tanHalfX_ = t, tanHalfY_ = t / aspect;
      else
        tanHalfY_ = t, tanHalfX_ = t * aspect;
      break;
    case FovAxis::Diagonal: {
      float diag = std::sqrt(aspect * aspect + 1);
      tanHalfX_ = t * aspect / diag, tanHalfY_ = t / diag;
      break;
    }
  }
  planeArea_ = 4 * tanHalfX_ * tanHalfY_;
}

Vec3f Camera::lensPoint(const Vec2f& uLens) const {
  if (!hasLens()) return position_;
  Vec2f disk = squareToConcentricDisk(uLens);
  return position_ + (right_ * disk.x + up_ * disk.y) * lensRadius_;
}

bool Camera::onLens(const Vec3f& p) const {
  const Vec3f offset = p - position_;
  // lensPoint's rounding: a few ulps of the position and of the radius.
  const float tolerance = 1e-5f * (maxAbsComponent(position_) + lensRadius_) + 1e-30f;
  if (!(std::fabs(dot(offset, forward_)) <= tolerance)) return false;
  return length(offset) <= lensRadius_ + tolerance;
}

Ray Camera::generateRay(const Vec2f& film, const Vec3f& lensPoint) const {
  float sx = (2 * film.x / width_ - 1) * tanHalfX_;
  float sy = (1 - 2 * film.y / height_) * tanHalfY_;
  Vec3f pinhole = forward_ + right_ * sx + up_ * sy;
  Ray r;
  r.o = lensPoint;
  if (!hasLens()) {
    r.d = normalize(pinhole);
  } else {
    // Towards the focus plane's point that the pinhole sees through the film point.
    const Vec3f focus = position_ + pinhole * focusDistance_;
    r.d = normalize(focus - lensPoint);
  }
  return r;
}

bool Camera::project(const Vec3f& lensPoint, const Vec3f& d, Vec2f* film) const {
  float c = dot(d, forward_);
  if (c <= 0) return false;
  Vec3f dir = d;
  if (hasLens()) {
    // Where the ray meets the focus plane, seen from the lens's centre.
    const Vec3f offset = lensPoint - position_;
    dir = offset + d * (focusDistance_ / c);
    c = dot(dir, forward_);
    if (!(c > 0)) return false;
  }
  float sx = dot(dir, right_) / c, sy = dot(dir, up_) / c;
  float fx = (sx / tanHalfX_ + 1) * 0.5f * width_;
  float fy = (1 - sy / tanHalfY_) * 0.5f * height_;
  if (!(fx >= 0 && fx < width_ && fy >= 0 && fy < height_)) return false;
  *film = Vec2f(fx, fy);
  return true;
}

float Camera::importance(const Vec3f& lensPoint, const Vec3f& d) const {
  Vec2f film;
  if (!project(lensPoint, d, &film)) return 0;
  float c = dot(d, forward_);
  return 1 / (planeArea_ * c * c * c);
}

}  // namespace farm
