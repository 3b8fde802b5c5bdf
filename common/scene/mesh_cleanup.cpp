#include "common/scene/mesh_cleanup.h"

#include <algorithm>
#include <cmath>

namespace farm {

namespace {

struct V3 {
  double x, y, z;
};
V3 sub(const Vec3f& a, const Vec3f& b) {
  return {double(a.x) - b.x, double(a.y) - b.y, double(a.z) - b.z};
}
double norm2(const V3& v) {
  return v.x * v.x + v.y * v.y + v.z * v.z;
}
bool samePoint(const Vec3f& a, const Vec3f& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}

}  // namespace

DegenerateTriangles removeDegenerateTriangles(ShapeDescription* mesh) {
  DegenerateTriangles d;
  if (mesh->type != ShapeDescription::Type::TriangleMesh) return d;
  std::vector<uint32_t>& idx = mesh->indices;
  const std::vector<Vec3f>& P = mesh->positions;
  size_t kept = 0;
  for (size_t t = 0; t + 2 < idx.size(); t += 3) {
    const uint32_t i0 = idx[t], i1 = idx[t + 1], i2 = idx[t + 2];
    const Vec3f &a = P[i0], &b = P[i1], &c = P[i2];
    bool bad = true;
    if (i0 == i1 || i1 == i2 || i0 == i2 || samePoint(a, b) || samePoint(b, c) || samePoint(a, c)) {
      ++d.repeatedVertex;
    } else {
      // In double, so that the test itself is not at the mercy of the rounding it measures.
      V3 e1 = sub(b, a), e2 = sub(c, a), e3 = sub(c, b);
      V3 n = {e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x};
      const double twiceArea = std::sqrt(norm2(n));
      const double longest = std::sqrt(std::max({norm2(e1), norm2(e2), norm2(e3)}));
      if (twiceArea == 0) {
        ++d.collinear;
      } else if (twiceArea / longest < kNeedleRatio * longest) {  // height = 2 area / base
        ++d.needle;
      } else {
        bad = false;
      }
    }
    if (bad) continue;
    idx[kept] = i0, idx[kept + 1] = i1, idx[kept + 2] = i2;
    kept += 3;
  }
  idx.resize(kept);
  return d;
}

std::string describe(const DegenerateTriangles& d) {
  std::string s = std::to_string(d.total()) + " degenerate triangle" + (d.total() == 1 ? "" : "s") +
                  " left out (";
  std::string parts;
  auto add = [&](int n, const char* what) {
    if (n == 0) return;
    if (!parts.empty()) parts += ", ";
    parts += std::to_string(n) + " " + what;
  };
  add(d.repeatedVertex, "repeated-vertex");
  add(d.collinear, "collinear (zero-area)");
  add(d.needle, "needle");
  return s + parts + ")";
}

}  // namespace farm
