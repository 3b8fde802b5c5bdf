#pragma once
// The renderer's scene: the description turned into Embree geometry, BSDFs, lights (lights.h) and
// the camera. Read-only after construction and shared by all threads of a process, except for the
// ray log a single-threaded benchmark may set (setRayLog).
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "common/scene/bsdf.h"
#include "common/scene/camera.h"
#include "common/scene/lights.h"
#include "common/scene/medium.h"
#include "common/scene/scene_description.h"

namespace farm {

// A stretch of a segment that lies in one medium: from `start` along unit d for `length`.
struct MediumSegment {
  int medium = -1;
  Vec3f start, d;
  float length = 0;
};

struct SurfaceHit {
  Vec3f p;   // on the surface (re-projected for accuracy)
  Vec3f ng;  // unit geometric normal, oriented as the shape defines it (outside)
  Vec3f ns;  // unit shading normal: interpolated vertex normals, else ng
  Vec2f uv;  // texture coordinates: interpolated vertex uvs, else (0, 0)
  float t = 0;
  int shape = -1;
  uint32_t primitive = 0;
};

// The rays a scene traced, for the benchmark that sets the estimators' ray rates beside Embree's
// own on the same rays (Scene::setRayLog, bench/render_bench.cpp).
struct RayLog {
  struct Entry {
    Vec3f o, d;
    float tFar;
    bool occlusion;  // an occlusion test, else a closest hit
    bool hit;        // what it found: something within tFar
  };
  std::vector<Entry> rays;
};

// The first-order geometry of a surface around one of its points, which the manifold walk
// differentiates specular constraints with (Jakob and Marschner 2012, section 4): an orthonormal
// basis (dpdu, dpdv) of the tangent plane (perpendicular to the geometric normal), the unit
// shading normal ns and its derivatives along dpdu and dpdv (zero where the shading normal is
// the face's own; the derivative of the normalized interpolated vertex normal on a smooth mesh).
struct SurfaceDifferential {
  Vec3f dpdu, dpdv;
  Vec3f ns, dndu, dndv;
};

// The adjoint BSDF with shading normals is not the BSDF (Veach 1997, eq. 5.17): particles
// (importance mode) scattered from wo to wi carry this extra factor.
inline float shadingCorrection(const Vec3f& wo, const Vec3f& wi, const Vec3f& ng, const Vec3f& ns) {
  float den = absDot(wo, ng) * absDot(wi, ns);
  return den > 0 ? absDot(wo, ns) * absDot(wi, ng) / den : 0.0f;
}

class Scene {
 public:
  // Taken by value: a loader's description moves in (a 10-million-triangle mesh is 180 MB of
  // positions and indices), a caller that keeps its own copies it.
  explicit Scene(SceneDescription desc);
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  const Camera& camera() const { return camera_; }
  const SceneDescription& description() const { return desc_; }
  int maxDepth() const { return desc_.maxDepth; }  // edges; -1 unbounded
  float extent() const { return extent_; }         // radius of the bounding sphere

  Vec3f center() const { return center_; }  // of the bounding sphere

  // The chance with which a path goes on from a vertex in a medium at p: 1 within twice the
  // reach of the scene (the bounding sphere widened to the camera and the point lights), and
  // beyond it the share of that sphere's solid angle seen from p, (2 reach / distance)^2, which
  // bounds what light from there can still bring back. Only a medium without a boundary (one
  // the camera or a light sits in, filling all space) puts vertices there: a path leaving the
  // scene through it scatters about 1 / sigma_t away (10^6 for an extinction of 1e-6) and would
  // walk on there to its roulette. A survival chance, with the survivor's weight divided by it,
  // leaves the estimate unbiased whatever its value (Russian roulette).
  float survivalBeyondReach(const Vec3f& p) const {
    const float d2 = lengthSquared(p - center_), r2 = 4 * reach_ * reach_;
    return d2 > r2 ? r2 / d2 : 1.0f;
  }

  // Whether direction w may leave or reach a surface point of geometric normal ng and shading
  // normal ns. With strict normals (Mitsuba's strictNormals, SceneDescription::strictNormals) only
  // where both normals put w on the same side: a path that would cross the surface by the one
  // and not the other has f = 0, so no light leaks through a smooth-shaded mesh, at the price of
  // the paths near its silhouette. Without, every direction: the BSDF, evaluated in the shading
  // frame, alone decides (Mitsuba with strictNormals false, Tungsten, pbrt-v4). Every sampler
  // and every evaluation of f asks here, so that all of them estimate the same integral.
  bool sidesAgree(const Vec3f& w, const Vec3f& ng, const Vec3f& ns) const {
    return !desc_.strictNormals || dot(w, ng) * dot(w, ns) > 0;
  }
  bool strictNormals() const { return desc_.strictNormals; }

  // Closest hit along r within (0, r.tMax); false when the ray leaves the scene.
  bool intersect(const Ray& r, SurfaceHit* hit) const;
  // While a log is set, every ray the scene traces (closest hits and occlusion tests, whichever
  // query asked) is appended to it. Not synchronized: set it only while one thread renders and
  // no other uses the scene (a benchmark's; nullptr, the default, logs nothing).
  void setRayLog(RayLog* log) const { rayLog_ = log; }
  // The logged rays traced by Embree alone, in their order, with nothing worked out of the hits:
  // what the hardware and Embree allow for that mix of rays. Returns how many hit.
  int64_t traceLoggedRays(const RayLog& log) const;
  // True when nothing blocks the segment between two points; pass n = 0 for a point (camera).
  bool visible(const Vec3f& p0, const Vec3f& n0, const Vec3f& p1, const Vec3f& n1) const;
  // True when nothing blocks the ray from p (geometric normal ng) in direction w: it reaches
  // the environment.
  bool escapes(const Vec3f& p, const Vec3f& ng, const Vec3f& w) const;
  // A ray leaving surface point p (geometric normal ng) in direction d, offset off the surface.
  Ray spawnRay(const Vec3f& p, const Vec3f& ng, const Vec3f& d) const;
  // How far spawnRay moves a ray's start off the surface at p.
  float offsetFor(const Vec3f& p) const;

  // Triangles of a mesh shape (1 for a sphere): the range of a path vertex's primitive.
  int primitiveCount(int shape) const;
  // The differential geometry at point p of triangle `primitive` of `shape` (any value for a
  // sphere), whose geometric normal there is ng; false for a degenerate triangle or an index out
  // of range.
  bool surfaceDifferential(int shape, int primitive, const Vec3f& p, const Vec3f& ng,
                           SurfaceDifferential* out) const;

  // Points of the specular shapes (those whose BSDF has only Dirac lobes), uniformly by area
  // over all of them: where manifold next-event estimation seeds its search for a specular
  // vertex. False when the scene has no specular surface.
  bool hasSpecularSurfaces() const { return !specularCdf_.empty(); }
  bool sampleSpecularSurface(const float u[3], Vec3f* p, Vec3f* n) const;
  // Whether specular shape `shape` is one smooth specular manifold: its shading normal turns
  // continuously over it (a sphere; a mesh whose triangles give one normal wherever their
  // corners meet, by interpolated vertex normals or by lying in one plane). Over a faceted
  // one (flat-shaded and curved: the water caustic's mesh with face normals) the normal jumps at
  // every edge, so each facet reflects a light into a point at most once and a manifold walk
  // reaches that solution only from a seed on its own facet: manifold next-event estimation's
  // trials would run into the ten thousands. False for a shape that is not specular.
  bool smoothSpecularShape(int shape) const {
    return shape >= 0 && size_t(shape) < smoothSpecular_.size() && smoothSpecular_[size_t(shape)];
  }
  // Whether any shape is (smoothSpecularShape).
  bool hasSmoothSpecularShape() const { return anySmoothSpecular_; }

  // The shape's BSDF as its description gives it: what does not depend on textures (its type,
  // its Dirac lobes) may be read here.
  const Bsdf& bsdfOf(int shape) const { return bsdfs_[shapeBsdf_[shape]]; }
  // The BSDF at one point of the shape, at texture coordinates uv: what evaluates and samples.
  Bsdf bsdfAt(int shape, const Vec2f& uv) const;
  int lightOf(int shape) const { return shapeLight_[shape]; }  // -1 when not an emitter

  // The lights: picking one, what they emit, and the densities of starting on them (lights.h).
  const Lights& lights() const { return lights_; }
  // A uniform point on area light `light` (its triangle by Lights::pickTriangle from u[0]), and
  // the emitting side's normal there; the area density is 1 / area.
  void sampleLightPoint(int light, const float u[3], Vec3f* p, Vec3f* n) const;

  // ---- Participating media ----
  // True when the scene has media or surfaces that only bound them: then rays pass null
  // boundaries (which visible() and escapes() would take for blockers) and lose light along the
  // way, and only the transport code that tracks media may render it.
  bool hasMedia() const { return tracksMedia_; }
  const Medium& medium(int i) const { return media_[size_t(i)]; }
  int cameraMedium() const { return desc_.camera.medium; }
  bool isNullBoundary(int shape) const { return desc_.shapes[size_t(shape)].nullBoundary; }
  // The medium on the side of a surface point (geometric normal ng) that direction w points
  // to, for a ray that was in `current`: the shape's exterior or interior medium when it has a
  // medium interface, else `current` (a surface without one leaves the medium as it is).
  int mediumOnSide(int shape, const Vec3f& ng, const Vec3f& w, int current) const;
  // The medium at point p, for where nothing says it (a light on a shape without a medium
  // interface): the side of the first medium boundary a ray from p meets that faces p, or
  // vacuum when the ray meets none.
  int mediumAt(const Vec3f& p) const;
  // The transmittance between two points (n = 0 for a point in a medium or on the camera),
  // starting in `medium` (-1: vacuum): 0 when a surface other than a null boundary blocks the
  // segment; the media crossed change at each null boundary. An unbiased estimate with numbers
  // from `stream` where a grid medium lies on the way; exact otherwise.
  Spectrum transmittance(const Vec3f& p0, const Vec3f& n0, const Vec3f& p1, const Vec3f& n1,
                         int medium, Sampler& sampler, SampleStream stream) const;
  // The same for the ray from p in direction w out of the scene (to the environment).
  Spectrum transmittanceToInfinity(const Vec3f& p, const Vec3f& n, const Vec3f& w, int medium,
                                   Sampler& sampler, SampleStream stream) const;
  // The stretches of the segment p0 - p1 that lie in media, from p0 on, as transmittance()
  // walks it (through null boundaries, starting in `medium`): false when another surface
  // blocks the segment (or it has no length). *arrival: the medium the walk ends in at p1.
  // Path-space MLT evaluates its transmittances and free-flight densities over these.
  bool mediumSegments(const Vec3f& p0, const Vec3f& n0, const Vec3f& p1, const Vec3f& n1,
                      int medium, std::vector<MediumSegment>* segments, int* arrival) const;

 private:
  // The walk along unit d from surface point `start` (its ray from o, offset off the surface)
  // to `end` (its ray to rayEnd), or to infinity when they are null, handing each stretch in a
  // medium to `visit` (which returns false to stop the walk there). True when the walk reached
  // the end, with *arrival (when not null) the medium it ended in.
  using SegmentVisitor = std::function<bool(const MediumSegment&)>;
  bool walkMedia(Vec3f start, Vec3f o, Vec3f d, const Vec3f* end, const Vec3f* rayEnd, int medium,
                 const SegmentVisitor& visit, int* arrival) const;
  // intersect(), with the hit's point and normals worked out only for a null boundary unless
  // everyShape (for another shape, only its shape, primitive and t).
  bool intersect(const Ray& r, SurfaceHit* hit, bool everyShape) const;
  // Whether anything lies on the ray from o along d before t = tFar.
  bool occluded(const Vec3f& o, const Vec3f& d, float tFar) const;
  // transmittance()'s walk.
  Spectrum transmittanceAlong(Vec3f start, Vec3f o, Vec3f d, const Vec3f* end, const Vec3f* rayEnd,
                              int medium, Sampler& sampler, SampleStream stream) const;

  // The ends of the segment p0 - p1 moved off their surfaces (n = 0: a point, not moved), each
  // to the side the segment leaves it by: where visibility and transmittance rays run between.
  void offsetEnds(const Vec3f& p0, const Vec3f& n0, const Vec3f& p1, const Vec3f& n1, Vec3f* o,
                  Vec3f* e) const;

  SceneDescription desc_;
  Camera camera_;
  std::vector<Bsdf> bsdfs_;
  std::vector<int> shapeBsdf_, shapeLight_;
  // Specular surfaces by area: the running total up to each (shape, triangle) entry.
  std::vector<double> specularCdf_;
  std::vector<std::pair<int, uint32_t>> specularPrimitives_;
  std::vector<char> smoothSpecular_;  // per shape, see smoothSpecularShape
  bool anySmoothSpecular_ = false;
  Lights lights_;
  float extent_ = 1;
  float reach_ = 1;  // see survivalBeyondReach
  Vec3f center_{0.0f};
  std::vector<Medium> media_;
  bool tracksMedia_ = false;
  void* device_ = nullptr;  // RTCDevice
  void* scene_ = nullptr;   // RTCScene
  bool hasNullBoundaries_ = false;
  mutable RayLog* rayLog_ = nullptr;
};

}  // namespace farm
