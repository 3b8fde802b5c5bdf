#pragma once
// The renderer's scene: the description turned into Embree geometry, BSDFs, area lights and the
// camera. Read-only after construction and shared by all threads of a process.
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "common/scene/bsdf.h"
#include "common/scene/camera.h"
#include "common/scene/environment_light.h"
#include "common/scene/medium.h"
#include "common/scene/point_light.h"
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

// The first-order geometry of a surface around one of its points, which the manifold walk
// differentiates specular constraints with (Jakob and Marschner 2012, section 4): an orthonormal
// basis (dpdu, dpdv) of the tangent plane (perpendicular to the geometric normal), the unit
// shading normal ns and its derivatives along dpdu and dpdv (zero where the shading normal is
// the face's own; the derivative of the normalized interpolated vertex normal on a smooth mesh).
struct SurfaceDifferential {
  Vec3f dpdu, dpdv;
  Vec3f ns, dndu, dndv;
};

// A light: one emitting shape, sampled uniformly by area, emitting on its normal's side; or a
// point light (point >= 0: Scene::pointLight()); or, with neither, the environment
// (Scene::environment()), whose path vertices lie at infinity.
struct AreaLight {
  int shape = -1;
  int point = -1;  // index into the scene's point lights
  Spectrum radiance;
  float area = 0;
  float power = 0;  // luminance of radiance * area * pi (twice for two sides): selection weight
  bool twoSided = false;  // an area light that emits on both sides of its surface
  bool isEnvironment() const { return shape < 0 && point < 0; }
  bool isPoint() const { return point >= 0; }
};

// The adjoint BSDF with shading normals is not the BSDF (Veach 1997, eq. 5.17): particles
// (importance mode) scattered from wo to wi carry this extra factor.
inline float shadingCorrection(const Vec3f& wo, const Vec3f& wi, const Vec3f& ng, const Vec3f& ns) {
  float den = absDot(wo, ng) * absDot(wi, ns);
  return den > 0 ? absDot(wo, ns) * absDot(wi, ng) / den : 0.0f;
}

class Scene {
 public:
  explicit Scene(const SceneDescription& desc);
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

  const std::vector<AreaLight>& lights() const { return lights_; }
  // Chooses a light in proportion to power; *pdf is its discrete probability.
  int pickLight(float u, float* pdf) const;
  float lightPickPdf(int light) const;
  // The density with which a light subpath starts where it does: pickLight's probability of the
  // light times that of the start on it, the area density 1 / area on an area light, the
  // coefficient 1 of a point light's delta, and the solid-angle density of the direction
  // `towardsEnvironment` for the environment. Every estimator's MIS weights take it from here
  // (pt's weight for a light it hits, BDPT's and the path-space chains' reverse densities, the
  // chains' seen emission), so that they agree with the sampling they weigh. In double: the
  // float quotients and products the estimators computed before are this, rounded.
  double lightStartDensity(int light, const Vec3f& towardsEnvironment = Vec3f(0.0f)) const;
  // The environment, or null; environmentLight() is its index among lights() (or -1).
  const EnvironmentLight* environment() const { return environment_.get(); }
  int environmentLight() const { return environmentLight_; }
  // Light subpaths leave the environment through a disk of the bounding sphere's radius facing
  // their direction, uniformly: this is the disk's area density (pbrt-v3's infinite light emits
  // the same way: a density of directions times one of positions on such a disk).
  float environmentDiskDensity() const { return 1 / (kPi * extent_ * extent_); }
  // The point of that disk for two uniform numbers, the disk facing unit direction w (towards
  // the environment) from outside the scene.
  Vec3f environmentDiskPoint(const Vec3f& w, const Vec2f& u) const;
  // Uniform point on an area light; the area density is 1 / area.
  void sampleLightPoint(int light, const float u[3], Vec3f* p, Vec3f* n) const;
  // The probability with which sampleLightPoint picks triangle t of a mesh light, as its CDF
  // makes it: what the area density 1 / area assumes to be area(t) / area. The CDFs are summed
  // in double so that this holds for 10^5 triangles of very different sizes (in float, a
  // triangle smaller than a rounding step of the running sum would get probability 0 or twice
  // its share).
  double trianglePickProbability(int light, uint32_t t) const;
  // The probability with which pickLight picks a light, as its CDF makes it.
  double lightPickProbability(int light) const;
  const PointLight& pointLight(int light) const { return pointLights_[lights_[light].point]; }
  // Radiance leaving light `light` in direction w at a point of normal n; for the environment,
  // the radiance travelling in direction w, and for a point light its intensity in direction w
  // (n is not used for either).
  Spectrum emitted(int light, const Vec3f& n, const Vec3f& w) const {
    if (light == environmentLight_) return environment_->radiance(-w);
    if (lights_[light].isPoint()) return pointLight(light).intensity(w);
    const float c = dot(n, w);
    return c > 0 || (lights_[light].twoSided && c < 0) ? lights_[light].radiance : Spectrum(0.0f);
  }
  // The solid-angle density with which an area light's subpaths leave it in direction w at a
  // point of normal n: cosine-weighted about n, on a side picked with probability 1/2 when the
  // light has two.
  float emissionPdf(int light, const Vec3f& n, const Vec3f& w) const {
    const float c = dot(n, w);
    return lights_[light].twoSided ? 0.5f * kInvPi * std::fabs(c) : (c > 0 ? c * kInvPi : 0.0f);
  }
  // A direction of an area light's emission, in its local frame (z along n), with emissionPdf's
  // density: cosine-weighted about z, or about -z for the back side, which a two-sided light
  // picks with the first number (rescaled, so that stratified numbers stay stratified).
  Vec3f sampleEmission(int light, Vec2f u) const;

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
  std::vector<std::vector<double>> triangleCdf_;  // per emitting mesh shape: area CDF
  // Specular surfaces by area: the running total up to each (shape, triangle) entry.
  std::vector<double> specularCdf_;
  std::vector<std::pair<int, uint32_t>> specularPrimitives_;
  std::vector<char> smoothSpecular_;  // per shape, see smoothSpecularShape
  bool anySmoothSpecular_ = false;
  std::vector<AreaLight> lights_;
  std::vector<double> lightCdf_;
  float extent_ = 1;
  float reach_ = 1;  // see survivalBeyondReach
  Vec3f center_{0.0f};
  std::unique_ptr<EnvironmentLight> environment_;
  std::vector<PointLight> pointLights_;
  int environmentLight_ = -1;
  std::vector<Medium> media_;
  bool tracksMedia_ = false;
  void* device_ = nullptr;  // RTCDevice
  void* scene_ = nullptr;   // RTCScene
  bool hasNullBoundaries_ = false;
};

}  // namespace farm
