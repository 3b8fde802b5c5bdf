#pragma once
// 4x4 affine transforms as Mitsuba writes them: row-major, column vectors (p' = M p).
#include <array>

#include "common/math/vec.h"

namespace farm {

struct Matrix4 {
  std::array<std::array<double, 4>, 4> m{};  // m[row][col]

  static Matrix4 identity();
  static Matrix4 translate(const Vec3f& t);
  static Matrix4 scale(const Vec3f& s);
  // Rotation by angleDegrees about axis (right-handed).
  static Matrix4 rotate(const Vec3f& axis, double angleDegrees);
  // Camera-to-world for an eye at `origin` looking at `target`, Mitsuba's lookat convention.
  static Matrix4 lookAt(const Vec3f& origin, const Vec3f& target, const Vec3f& up);

  Matrix4 operator*(const Matrix4& o) const;
  Matrix4 inverse() const;  // general 4x4 inverse; returns all-NaN for a singular matrix
  Matrix4 transpose() const;
  bool isFinite() const;

  Vec3f applyPoint(const Vec3f& p) const;
  Vec3f applyVector(const Vec3f& v) const;
  // Normals transform with the inverse transpose; pass the inverse once when transforming many.
  Vec3f applyNormal(const Vec3f& n) const;
};

}  // namespace farm
