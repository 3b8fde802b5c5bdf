#include "common/scene/camera.h"

#include <cmath>

namespace farm {

Camera::Camera(const CameraDescription& desc) : width_(desc.width), height_(desc.height) {
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

Ray Camera::generateRay(const Vec2f& film) const {
  float sx = (2 * film.x / width_ - 1) * tanHalfX_;
  float sy = (1 - 2 * film.y / height_) * tanHalfY_;
  Ray r;
  r.o = position_;
  r.d = normalize(forward_ + right_ * sx + up_ * sy);
  return r;
}

bool Camera::project(const Vec3f& d, Vec2f* film) const {
  float c = dot(d, forward_);
  if (c <= 0) return false;
  float sx = dot(d, right_) / c, sy = dot(d, up_) / c;
  float fx = (sx / tanHalfX_ + 1) * 0.5f * width_;
  float fy = (1 - sy / tanHalfY_) * 0.5f * height_;
  if (!(fx >= 0 && fx < width_ && fy >= 0 && fy < height_)) return false;
  *film = Vec2f(fx, fy);
  return true;
}

float Camera::importance(const Vec3f& d) const {
  Vec2f film;
  if (!project(d, &film)) return 0;
  float c = dot(d, forward_);
  return 1 / (planeArea_ * c * c * c);
}

}  // namespace farm
