#pragma once
// A vertex of a light path, as the bidirectional tracer builds it and the path-space
// mutations edit it, and the densities every sampling strategy gives a whole path.
#include <cstdint>

#include "common/math/vec.h"

namespace farm {

class Scene;
struct SurfaceHit;

struct PathVertex {
  // Medium: a scattering event inside a participating medium (no surface: n and ns are zero,
  // the phase function scatters, and no cosine enters its geometric factors).
  enum class Kind : uint8_t { Camera, Light, Surface, Medium };
  Kind kind = Kind::Surface;
  Vec3f p;
  Vec3f n;   // geometric normal; zero for the (pinhole) camera and in media; at infinity, see
             // atInfinity
  Vec3f ns;  // shading normal (the BSDF's frame); n for lights, zero for the camera
  Vec3f wo;  // unit direction to the previous vertex of its own subpath
  Vec2f uv;  // texture coordinates, where the BSDF is looked up (Scene::bsdfAt)
  int shape = -1;
  int primitive = -1;  // the shape's triangle (0 for a sphere), or -1 where not known
  int light = -1;      // the area light this vertex lies on, or -1
  // The participating medium (Scene::medium, -1 for vacuum) that the vertex lies in: for a
  // surface, the one its subpath arrived through (a surface without a medium interface has it
  // on both sides); for a light, the one around it.
  int medium = -1;
  Spectrum beta;          // subpath throughput up to here, divided by the sampling densities
  float pdfFwd = 0;       // area density of this vertex, sampled from its own subpath's side
  float pdfRev = 0;       // area density of this vertex, sampled from the other side
  bool delta = false;     // scattered by a Dirac lobe here
  bool infinite = false;  // on the environment, at infinity (see atInfinity)
};

// A vertex on the environment: a light vertex without a shape, at infinity. Its n is the unit
// direction its light travels in (into the scene), p a point far along the other way (never
// used for directions: see directionBetween), and its densities are solid-angle densities of
// that direction, from either side; the vertex after it, sampled from its side, has the area
// density of the environment's disk times that vertex's cosine (Lights::environmentDiskDensity).
inline bool atInfinity(const PathVertex& v) {
  return v.kind == PathVertex::Kind::Light && v.infinite;
}

// A vertex on a point light: a light vertex without a shape, not at infinity. Its n is zero (a
// point has no side); it is sampled only from the light side, with the probability of picking
// its light (the coefficient of its positional delta), and no camera path ever reaches it.
inline bool onPointLight(const PathVertex& v) {
  return v.kind == PathVertex::Kind::Light && v.shape < 0 && !v.infinite;
}

// The surface vertex at a ray's hit: position, normals, texture coordinates, shape, triangle
// and light (the rest left at their defaults).
PathVertex surfaceVertex(const Scene& scene, const SurfaceHit& hit);

// The vertex at infinity that a ray from `from` in unit direction w reaches when it leaves the
// scene: on the environment light `light`, its light travelling along -w.
PathVertex vertexAtInfinity(const Scene& scene, int light, const Vec3f& from, const Vec3f& w);

inline bool inMedium(const PathVertex& v) {
  return v.kind == PathVertex::Kind::Medium;
}

// The cosine that converts densities and geometric factors at v for direction w: the geometric
// normal's, and 1 in a medium (where a density per solid angle is one per volume times d^2).
inline float cosineAt(const PathVertex& v, const Vec3f& w) {
  return inMedium(v) ? 1.0f : absDot(v.n, w);
}

// The unit direction from a to b, either of which may lie at infinity.
inline Vec3f directionBetween(const PathVertex& a, const PathVertex& b) {
  if (atInfinity(a)) return a.n;
  if (atInfinity(b)) return -b.n;
  return normalize(b.p - a.p);
}

// Converts a solid-angle density at `from` towards `to` into an area density at `to` (the
// geometric normal's cosine over the squared distance; 1 / d^2 at the normal-less camera).
double toAreaDensity(double pdfSolidAngle, const Vec3f& from, const Vec3f& to, const Vec3f& toN);

// The densities of every vertex of a whole path x_0 .. x_{n-1} (x_0 on a light, x_{n-1} the
// camera) computed from the vertices alone, in one fixed order of operations: pL[i] is the area
// density of x_i sampled from the light side (x_0 by light selection and area sampling, x_1 by
// emission, then by the BSDFs), pE[i] from the camera side. Where a Dirac lobe samples the
// vertex, the lobe's selection probability times the geometric factor (the coefficient of the
// delta function); zero where nothing can sample it (the camera from the light side, the pinhole
// from the camera side). MIS treats the Dirac entries as common factors. Strategy (s, t = n - s)
// has density prod_{i<s} pL[i] prod_{i>=s} pE[i] (Veach 1997, eq. 10.8). `path[i]` points at x_i;
// `delta[i]` receives whether x_i scatters only through Dirac lobes.
void pathDensities(const Scene& scene, const PathVertex* const* path, int n, double* pL, double* pE,
                   char* delta);

// The strategy s (light vertices) of largest density among those that can build the path, ties
// to the fewer light vertices: the maximum heuristic's winner (Veach and Guibas 1994). One
// function of the densities above, so that every strategy that evaluates the path agrees on it.
// `pointLight`: x_0 is on a point light, which no strategy without light vertices builds.
int maximumHeuristicStrategy(const double* pL, const double* pE, const char* delta, int n,
                             bool pointLight = false);

}  // namespace farm
