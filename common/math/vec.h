#pragma once
// Small fixed-size vectors for geometry and RGB. Float storage: Embree works in float and the
// transport code keeps its throughputs in float; image accumulation happens in double elsewhere.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace farm {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

struct Vec2f {
  float x = 0, y = 0;
  constexpr Vec2f() = default;
  constexpr Vec2f(float x_, float y_) : x(x_), y(y_) {}
};

struct Vec3f {
  float x = 0, y = 0, z = 0;
  constexpr Vec3f() = default;
  constexpr explicit Vec3f(float v) : x(v), y(v), z(v) {}
  constexpr Vec3f(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3f operator-() const { return {-x, -y, -z}; }
  Vec3f& operator+=(const Vec3f& o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  Vec3f& operator-=(const Vec3f& o) {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  Vec3f& operator*=(const Vec3f& o) {
    x *= o.x;
    y *= o.y;
    z *= o.z;
    return *this;
  }
  Vec3f& operator*=(float s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
  Vec3f& operator/=(float s) {
    float inv = 1.0f / s;
    x *= inv;
    y *= inv;
    z *= inv;
    return *this;
  }
};

constexpr Vec3f operator+(const Vec3f& a, const Vec3f& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
constexpr Vec3f operator-(const Vec3f& a, const Vec3f& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
constexpr Vec3f operator*(const Vec3f& a, const Vec3f& b) {
  return {a.x * b.x, a.y * b.y, a.z * b.z};
}
constexpr Vec3f operator*(const Vec3f& a, float s) {
  return {a.x * s, a.y * s, a.z * s};
}
constexpr Vec3f operator*(float s, const Vec3f& a) {
  return {a.x * s, a.y * s, a.z * s};
}
inline Vec3f operator/(const Vec3f& a, float s) {
  float inv = 1.0f / s;
  return a * inv;
}
inline Vec3f operator/(const Vec3f& a, const Vec3f& b) {
  return {a.x / b.x, a.y / b.y, a.z / b.z};
}

constexpr float dot(const Vec3f& a, const Vec3f& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline float absDot(const Vec3f& a, const Vec3f& b) {
  return std::fabs(dot(a, b));
}
constexpr Vec3f cross(const Vec3f& a, const Vec3f& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float lengthSquared(const Vec3f& a) {
  return dot(a, a);
}
inline float length(const Vec3f& a) {
  return std::sqrt(dot(a, a));
}
inline Vec3f normalize(const Vec3f& a) {
  return a / length(a);
}
inline float maxComponent(const Vec3f& a) {
  return std::max(a.x, std::max(a.y, a.z));
}
inline float maxAbsComponent(const Vec3f& a) {
  return std::max(std::fabs(a.x), std::max(std::fabs(a.y), std::fabs(a.z)));
}
inline Vec3f vmin(const Vec3f& a, const Vec3f& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3f vmax(const Vec3f& a, const Vec3f& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
inline bool isFinite(const Vec3f& a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
inline Vec3f faceForward(const Vec3f& n, const Vec3f& v) {
  return dot(n, v) < 0 ? -n : n;
}

// RGB radiance / importance / throughput. Same storage as a vector; the alias documents intent.
using Spectrum = Vec3f;
inline bool isBlack(const Spectrum& s) {
  return s.x == 0 && s.y == 0 && s.z == 0;
}
// The scalar contribution (docs/design.md): luminance with Rec. 709 weights.
inline float luminance(const Spectrum& s) {
  return 0.2126f * s.x + 0.7152f * s.y + 0.0722f * s.z;
}
// A splat value is usable when it is finite and has no negative channel.
inline bool isValidRadiance(const Spectrum& s) {
  return isFinite(s) && s.x >= 0 && s.y >= 0 && s.z >= 0;
}

// Orthonormal basis around a unit normal (Duff et al. 2017, "Building an orthonormal basis,
// revisited"), used as the local shading frame: z is the normal.
struct Frame {
  Vec3f s, t, n;
  Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
  explicit Frame(const Vec3f& normal) : n(normal) {
    float sign = std::copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    s = Vec3f(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    t = Vec3f(b, sign + n.y * n.y * a, -n.y);
  }
  Vec3f toLocal(const Vec3f& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3f toWorld(const Vec3f& v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace farm
