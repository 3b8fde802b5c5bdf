#include "common/transport/specular_manifold.h"

#include <cmath>
#include <vector>

#include "common/scene/scene.h"

namespace farm {

namespace {

// Double precision for the linear algebra: the blocks of a long chain can differ by orders of
// magnitude, and the determinant of their product is what the density carries.
struct V3 {
  double x = 0, y = 0, z = 0;
  V3() = default;
  V3(double a, double b, double c) : x(a), y(b), z(c) {}
  explicit V3(const Vec3f& v) : x(v.x), y(v.y), z(v.z) {}
  V3 operator+(const V3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  V3 operator-(const V3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  V3 operator*(double s) const { return {x * s, y * s, z * s}; }
};
double dot(const V3& a, const V3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
double norm(const V3& a) {
  return std::sqrt(dot(a, a));
}

// (I - w w^T) v / d: the change of the unit direction w = (q - p) / |q - p| when q moves by v.
V3 directionChange(const V3& w, double d, const V3& v) {
  return (v - w * dot(w, v)) * (1 / d);
}

Matrix2 operator*(const Matrix2& a, const Matrix2& b) {
  Matrix2 r;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j];
  return r;
}
Matrix2 operator-(const Matrix2& a, const Matrix2& b) {
  Matrix2 r;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) r.m[i][j] = a.m[i][j] - b.m[i][j];
  return r;
}
bool inverse(const Matrix2& a, Matrix2* out) {
  const double det = a.determinant();
  const double scale =
      std::fabs(a.m[0][0]) + std::fabs(a.m[0][1]) + std::fabs(a.m[1][0]) + std::fabs(a.m[1][1]);
  if (!(std::fabs(det) > 1e-14 * scale * scale) || !std::isfinite(det)) return false;
  out->m[0][0] = a.m[1][1] / det;
  out->m[0][1] = -a.m[0][1] / det;
  out->m[1][0] = -a.m[1][0] / det;
  out->m[1][1] = a.m[0][0] / det;
  return true;
}

struct VertexGeometry {
  V3 p, dpdu, dpdv;  // position and tangent basis of the surface
  V3 n, dndu, dndv;  // shading normal and its derivatives (specular vertices only)
};

// An end of the chain needs only its tangent plane (its normal does not enter a constraint); a
// point light's is empty, as it never moves.
bool geometryOf(const Scene& scene, const PathVertex& v, bool specular, VertexGeometry* g) {
  g->p = V3(v.p);
  if (!specular) {
    if (v.shape < 0) return true;
    const Frame tangent(v.n);
    g->dpdu = V3(tangent.s), g->dpdv = V3(tangent.t);
    return true;
  }
  SurfaceDifferential d;
  if (!scene.surfaceDifferential(v.shape, v.primitive, v.p, v.n, &d)) return false;
  g->dpdu = V3(d.dpdu), g->dpdv = V3(d.dpdv);
  g->n = V3(d.ns), g->dndu = V3(d.dndu), g->dndv = V3(d.dndv);
  return true;
}

// The three 2 x 2 blocks of constraint i's derivative: with respect to x_{i-1}, x_i and x_{i+1}.
struct ConstraintBlocks {
  Matrix2 previous, self, next;
};

bool constraintBlocks(const Scene& scene, const PathVertex& v, const VertexGeometry& prev,
                      const VertexGeometry& g, const VertexGeometry& next, ConstraintBlocks* out) {
  V3 wi = prev.p - g.p, wo = next.p - g.p;
  const double di = norm(wi), dout = norm(wo);
  if (!(di > 0) || !(dout > 0)) return false;
  wi = wi * (1 / di);
  wo = wo * (1 / dout);
  // Indices of refraction on each side: a refraction joins the two media of a dielectric, a
  // reflection stays in one (its index then scales h alone and is left out).
  double etaI = 1, etaO = 1;
  const double ci = dot(wi, g.n), co = dot(wo, g.n);
  if (ci * co < 0) {
    float intIOR, extIOR;
    if (!scene.bsdfOf(v.shape).smoothDielectricIndices(&intIOR, &extIOR)) return false;
    etaI = ci > 0 ? extIOR : intIOR;
    etaO = co > 0 ? extIOR : intIOR;
  }
  const V3 h = wi * etaI + wo * etaO;
  const double hn = dot(h, g.n);
  // A tangent frame of the shading normal.
  const Frame frame(Vec3f(float(g.n.x), float(g.n.y), float(g.n.z)));
  const V3 s(frame.s), t(frame.t);
  // d h / d x_{i-1} = eta_i (I - wi wi^T) / di, d h / d x_{i+1} likewise, d h / d x_i = minus
  // their sum; the frame turns with the normal: d (s . h) = s . dh - (h . n) (s . dn) where h
  // is parallel to n (the chain satisfies its constraints).
  const V3* prevBasis[2] = {&prev.dpdu, &prev.dpdv};
  const V3* basis[2] = {&g.dpdu, &g.dpdv};
  const V3* nextBasis[2] = {&next.dpdu, &next.dpdv};
  const V3* normalChange[2] = {&g.dndu, &g.dndv};
  for (int c = 0; c < 2; ++c) {
    const V3 dPrev = directionChange(wi, di, *prevBasis[c]) * etaI;
    const V3 dNext = directionChange(wo, dout, *nextBasis[c]) * etaO;
    const V3 dSelf =
        (directionChange(wi, di, *basis[c]) * etaI + directionChange(wo, dout, *basis[c]) * etaO) *
        -1.0;
    out->previous.m[0][c] = dot(s, dPrev);
    out->previous.m[1][c] = dot(t, dPrev);
    out->next.m[0][c] = dot(s, dNext);
    out->next.m[1][c] = dot(t, dNext);
    out->self.m[0][c] = dot(s, dSelf) - hn * dot(s, *normalChange[c]);
    out->self.m[1][c] = dot(t, dSelf) - hn * dot(t, *normalChange[c]);
  }
  return true;
}

}  // namespace

bool isSpecularChain(const Scene& scene, const Path& x, int a, int b) {
  if (a < 0 || b >= int(x.vertices.size()) || a + 1 >= b) return false;
  const PathVertex& start = x[a];
  if (atInfinity(start) || x.isSpecular(scene, a)) return false;
  if (start.kind == PathVertex::Kind::Camera) return false;
  const PathVertex& end = x[b];
  if (end.kind != PathVertex::Kind::Surface || x.isSpecular(scene, b) || end.shape < 0)
    return false;
  for (int i = a + 1; i < b; ++i) {
    if (!x.isSpecular(scene, i) || x[i].primitive < 0) return false;
  }
  return true;
}

namespace {
// specularChainDerivative's arrays (see there).
struct ChainSystem {
  std::vector<VertexGeometry> geometry;
  std::vector<ConstraintBlocks> blocks;
  std::vector<Matrix2> diag, rhs, solution;
};
}  // namespace

bool specularChainDerivative(const Scene& scene, const Path& x, int a, int b, bool moveEnd,
                             Matrix2* derivative) {
  if (!isSpecularChain(scene, x, a, b)) return false;
  if (!moveEnd && x[a].shape < 0) return false;  // a point light does not move
  const int n = b - a - 1;                       // specular vertices, rows of the system
  // The solve's arrays, kept per thread and refilled: the manifold walk solves at every step of
  // every walk (17 million times in a few seconds of the water caustic's bootstrap and chains),
  // and five fresh vectors a time were the chains' largest allocation (docs/speed.md).
  thread_local ChainSystem system;
  std::vector<VertexGeometry>& g = system.geometry;
  g.assign(static_cast<size_t>(n + 2), VertexGeometry());
  for (int i = 0; i < n + 2; ++i) {
    if (!geometryOf(scene, x[a + i], i > 0 && i <= n, &g[size_t(i)])) return false;
  }
  std::vector<ConstraintBlocks>& blocks = system.blocks;
  blocks.assign(static_cast<size_t>(n), ConstraintBlocks());
  for (int r = 0; r < n; ++r) {
    if (!constraintBlocks(scene, x[a + 1 + r], g[size_t(r)], g[size_t(r + 1)], g[size_t(r + 2)],
                          &blocks[size_t(r)]))
      return false;
  }
  // A du = rhs with A block tridiagonal (rows r: previous, self, next) and the moved end's
  // column on the right: -next of the last row (moveEnd) or -previous of the first.
  // Block Thomas algorithm: forward elimination, then back substitution.
  std::vector<Matrix2>&diag = system.diag, &rhs = system.rhs;
  diag.assign(static_cast<size_t>(n), Matrix2());
  rhs.assign(static_cast<size_t>(n), Matrix2());
  for (int r = 0; r < n; ++r) diag[size_t(r)] = blocks[size_t(r)].self;
  Matrix2 zero;
  for (int r = 0; r < n; ++r) rhs[size_t(r)] = zero;
  if (moveEnd) {
    rhs[size_t(n - 1)] = zero - blocks[size_t(n - 1)].next;
  } else {
    rhs[0] = zero - blocks[0].previous;
  }
  for (int r = 1; r < n; ++r) {
    Matrix2 inv;
    if (!inverse(diag[size_t(r - 1)], &inv)) return false;
    const Matrix2 w = blocks[size_t(r)].previous * inv;
    diag[size_t(r)] = diag[size_t(r)] - w * blocks[size_t(r - 1)].next;
    rhs[size_t(r)] = rhs[size_t(r)] - w * rhs[size_t(r - 1)];
  }
  std::vector<Matrix2>& solution = system.solution;
  solution.assign(static_cast<size_t>(n), Matrix2());
  for (int r = n - 1; r >= 0; --r) {
    Matrix2 inv;
    if (!inverse(diag[size_t(r)], &inv)) return false;
    Matrix2 right = rhs[size_t(r)];
    if (r + 1 < n) right = right - blocks[size_t(r)].next * solution[size_t(r + 1)];
    solution[size_t(r)] = inv * right;
  }
  *derivative = moveEnd ? solution[0] : solution[size_t(n - 1)];
  for (const auto& row : derivative->m)
    for (double v : row)
      if (!std::isfinite(v)) return false;
  return true;
}

double chainSolidAnglePerArea(const Scene& scene, const Path& x, int a, int b, bool moveEnd) {
  Matrix2 d;
  if (!specularChainDerivative(scene, x, a, b, moveEnd, &d)) return 0;
  // The neighbour of the held end moves in its tangent plane by d du; seen from the held end
  // that is a solid angle of cos / dist^2 per unit of its area.
  const double conversion =
      moveEnd ? geometricConversion(x[a], x[a + 1]) : geometricConversion(x[b], x[b - 1]);
  return conversion * std::fabs(d.determinant());
}

double logSpecularChainMeasureRatio(const Scene& scene, const Path& x, int a, int b) {
  Matrix2 d;
  if (!specularChainDerivative(scene, x, a, b, true, &d)) return -INFINITY;
  double logRatio = -std::log(std::fabs(d.determinant()));
  for (int j = a + 1; j < b; ++j) {
    logRatio += std::log(geometricConversion(x[j], x[j + 1]));
    const PathVertex& v = x[j];
    const Frame frame(v.ns);
    logRatio += std::log(double(scene.bsdfOf(v.shape).diracJacobian(
        frame.toLocal(normalize(x[j - 1].p - v.p)), frame.toLocal(normalize(x[j + 1].p - v.p)))));
  }
  return std::isfinite(logRatio) ? logRatio : -INFINITY;
}

}  // namespace farm
