#include "common/math/transform.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace farm {

namespace {
constexpr double kPiDouble = 3.14159265358979323846;
}  // namespace

Matrix4 Matrix4::identity() {
  Matrix4 r;
  for (int i = 0; i < 4; ++i) r.m[i][i] = 1.0;
  return r;
}

Matrix4 Matrix4::translate(const Vec3f& t) {
  Matrix4 r = identity();
  r.m[0][3] = t.x;
  r.m[1][3] = t.y;
  r.m[2][3] = t.z;
  return r;
}

Matrix4 Matrix4::scale(const Vec3f& s) {
  Matrix4 r = identity();
  r.m[0][0] = s.x;
  r.m[1][1] = s.y;
  r.m[2][2] = s.z;
  return r;
}

Matrix4 Matrix4::rotate(const Vec3f& axis, double angleDegrees) {
  // Rodrigues' formula, R = cos I + sin [a]x + (1 - cos) a a^T, in double so that composing many
  // small rotations does not drift.
  double x = axis.x, y = axis.y, z = axis.z;
  double len = std::sqrt(x * x + y * y + z * z);
  x /= len;
  y /= len;
  z /= len;
  double theta = angleDegrees * (kPiDouble / 180.0);
  double s = std::sin(theta), c = std::cos(theta), t = 1.0 - c;
  Matrix4 r = identity();
  r.m[0][0] = t * x * x + c;
  r.m[0][1] = t * x * y - s * z;
  r.m[0][2] = t * x * z + s * y;
  r.m[1][0] = t * x * y + s * z;
  r.m[1][1] = t * y * y + c;
  r.m[1][2] = t * y * z - s * x;
  r.m[2][0] = t * x * z - s * y;
  r.m[2][1] = t * y * z + s * x;
  r.m[2][2] = t * z * z + c;
  return r;
}

Matrix4 Matrix4::lookAt(const Vec3f& origin, const Vec3f& target, const Vec3f& up) {
  // Mitsuba's convention: the camera looks down its +z, +y is up and +x = up x dir points to the
  // image's left. The columns of the camera-to-world matrix are those axes and the eye position.
  auto normalized = [](double v[3]) {
    double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int i = 0; i < 3; ++i) v[i] /= len;
  };
  auto crossd = [](const double a[3], const double b[3], double out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
  };
  double dir[3] = {double(target.x) - origin.x, double(target.y) - origin.y,
                   double(target.z) - origin.z};
  normalized(dir);
  double u[3] = {up.x, up.y, up.z};
  double left[3], newUp[3];
  crossd(u, dir, left);
  normalized(left);  // NaN when up is parallel to the view direction; callers check isFinite()
  crossd(dir, left, newUp);
  Matrix4 r = identity();
  for (int i = 0; i < 3; ++i) {
    r.m[i][0] = left[i];
    r.m[i][1] = newUp[i];
    r.m[i][2] = dir[i];
  }
  r.m[0][3] = origin.x;
  r.m[1][3] = origin.y;
  r.m[2][3] = origin.z;
  return r;
}

Matrix4 Matrix4::operator*(const Matrix4& o) const {
  Matrix4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += m[i][k] * o.m[k][j];
      r.m[i][j] = s;
    }
  return r;
}

Matrix4 Matrix4::inverse() const {
  // Gauss-Jordan elimination with partial pivoting.
  Matrix4 singular;
  for (auto& row : singular.m) row.fill(std::numeric_limits<double>::quiet_NaN());
  if (!isFinite()) return singular;
  double a[4][8];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      a[i][j] = m[i][j];
      a[i][j + 4] = i == j ? 1.0 : 0.0;
    }
  for (int col = 0; col < 4; ++col) {
    int pivot = col;
    for (int r = col + 1; r < 4; ++r)
      if (std::fabs(a[r][col]) > std::fabs(a[pivot][col])) pivot = r;
    if (a[pivot][col] == 0.0) return singular;
    if (pivot != col) std::swap(a[pivot], a[col]);
    double inv = 1.0 / a[col][col];
    for (int j = 0; j < 8; ++j) a[col][j] *= inv;
    for (int r = 0; r < 4; ++r) {
      if (r == col || a[r][col] == 0.0) continue;
      double f = a[r][col];
      for (int j = 0; j < 8; ++j) a[r][j] -= f * a[col][j];
    }
  }
  Matrix4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r.m[i][j] = a[i][j + 4];
  // A matrix that is singular in exact arithmetic usually leaves a rounding-error pivot rather
  // than zero, and an "inverse" of enormous entries. M * M^-1 = I then fails by far, while it
  // holds to rounding for any usable transform, however large its translation or small its scale
  // (a pivot threshold against the largest entry would reject those).
  Matrix4 check = *this * r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (!(std::fabs(check.m[i][j] - (i == j ? 1.0 : 0.0)) <= 1e-6)) return singular;
  return r;
}

Matrix4 Matrix4::transpose() const {
  Matrix4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
  return r;
}

bool Matrix4::isFinite() const {
  for (const auto& row : m)
    for (double v : row)
      if (!std::isfinite(v)) return false;
  return true;
}

Vec3f Matrix4::applyPoint(const Vec3f& p) const {
  double r[4];
  for (int i = 0; i < 4; ++i) r[i] = m[i][0] * p.x + m[i][1] * p.y + m[i][2] * p.z + m[i][3];
  // Affine matrices have w = 1; a projective bottom row is honoured rather than silently dropped.
  if (r[3] != 1.0) {
    double inv = 1.0 / r[3];
    for (int i = 0; i < 3; ++i) r[i] *= inv;
  }
  return {float(r[0]), float(r[1]), float(r[2])};
}

Vec3f Matrix4::applyVector(const Vec3f& v) const {
  return {float(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z),
          float(m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z),
          float(m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z)};
}

Vec3f Matrix4::applyNormal(const Vec3f& n) const {
  // (M^-1)^T n: the result is not normalized (callers that need a unit normal normalize it), so
  // that a caller can also use its length, e.g. for area scaling.
  return inverse().transpose().applyVector(n);
}

}  // namespace farm
