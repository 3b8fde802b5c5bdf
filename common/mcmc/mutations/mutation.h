#pragma once
// Veach's mutations of path-space MLT (Veach and Guibas 1997; Veach 1997, ch. 11), each a class
// behind this interface in the manner of Mitsuba 0.6's bidir/mutator.h: propose y from the
// chain's current path x, and evaluate the transition density T(y | x) of the move it made. The
// chain accepts with min(1, f(y) T(x | y) / (f(x) T(y | x))) computed in logarithms, and evaluates
// T(x | y) by calling logDensity() on the reverse move, from y's vertices alone.
//
// Every mutation here replaces one contiguous run of vertices: it keeps the first keptLight
// vertices of x (x_0 ..) and its last keptCamera ones (.. x_k, the camera among them), and puts
// `added` new vertices where x had `removed`. The reverse move keeps the same ends and swaps the
// two counts. Densities follow Path's convention: area densities, with the coefficient of the
// delta function at specular vertices, in the direction towards the light.
#include <cstdint>

#include "common/sampling/rng.h"
#include "common/scene/bsdf.h"
#include "common/transport/path.h"

namespace farm {

class Camera;
class Scene;

enum class MutationType : uint8_t {
  Bidirectional,
  LensSubpath,
  LensPerturbation,
  CausticPerturbation,
  MultiChainPerturbation,
  ManifoldPerturbation,
};
constexpr int kMutationTypes = 6;
const char* mutationName(MutationType type);  // "bidir", "lens-subpath", "lens", ...

struct MutationRecord {
  MutationType type = MutationType::Bidirectional;
  int keptLight = 0;   // vertices kept at the light end
  int keptCamera = 1;  // vertices kept at the camera end (at least the camera)
  int removed = 0;     // x's vertices between them
  int added = 0;       // y's vertices between them
  MutationRecord reverse() const {
    MutationRecord r = *this;
    r.removed = added;
    r.added = removed;
    return r;
  }
};

// What every mutation needs: the scene, the longest path the target allows, and a count of the
// rays it traced (for rays per second).
struct MutationContext {
  const Scene& scene;
  int maxDepth;  // edges; < 0 unbounded
  mutable uint64_t rays = 0;
};

class Mutation {
 public:
  explicit Mutation(const MutationContext& context) : context_(context) {}
  virtual ~Mutation() = default;
  virtual MutationType type() const = 0;
  // Whether the mutation can move x at all; the chain picks among those that can.
  virtual bool appliesTo(const Path& x) const = 0;
  // Proposes y from x with numbers from rng; false when the attempt built no path (the chain
  // counts it as a rejection). y's vertices need not carry light: the chain evaluates f(y).
  virtual bool propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const = 0;
  // log T(to | from) for the move `record` describes; -infinity when it cannot make `to`.
  virtual double logDensity(const Path& from, const Path& to,
                            const MutationRecord& record) const = 0;

 protected:
  const MutationContext& context_;
};

// --- Helpers the mutations share -------------------------------------------------------------

// The surface the ray from vertex `from` in direction w hits first (passing null boundaries,
// which only bound media), as a path vertex; false when the ray leaves the scene. Counts the
// rays. The perturbations move surface vertices by it: their proposals ignore media, which
// enter only f.
bool traceVertex(const MutationContext& context, const PathVertex& from, const Vec3f& w,
                 PathVertex* hit);
// The same, except that a ray leaving a scene with an environment light ends on it, at infinity
// (*escaped set): how camera subpaths end there, as BDPT's do. Without media only (path-space
// chains take an environment only in scenes without media).
bool traceOrEscape(const MutationContext& context, const PathVertex& from, const Vec3f& w,
                   PathVertex* hit, bool* escaped);
// The vertex that a flight from `from` in direction w reaches: the first surface, or a vertex
// in a medium where Medium::sampleFreeFlight lands one in a medium on the way (the flight
// starting in `medium`, changing medium at null boundaries); the vertex's `medium` is the one
// it arrived in. Path::freeFlightDensity gives its density. Without media, traceVertex.
bool flyVertex(const MutationContext& context, const PathVertex& from, int medium, const Vec3f& w,
               Rng& rng, PathVertex* hit);
// One step of a random walk: the vertex after `at` (which was reached from `from`, and lies in
// medium `around`), its direction sampled by the BSDF at `at` in the given transport mode, or
// by the phase function of the medium `at` lies in, and the flight along it by flyVertex.
// `mayEscape`: a ray that leaves the scene ends on the environment (traceOrEscape), for a camera
// side's vertex that becomes x_0. Path::densities and Path::freeFlightDensity give the
// vertex's density.
bool scatterVertex(const MutationContext& context, const PathVertex& at, const PathVertex& from,
                   int around, TransportMode mode, bool mayEscape, Rng& rng, PathVertex* next);
// The medium that a path leaving v in direction w starts in, `around` being the medium around
// v (on either side of a surface without a medium interface).
int mediumLeaving(const Scene& scene, const PathVertex& v, const Vec3f& w, int around);
// Whether the segment between two vertices is unoccluded (null boundaries let it through); with
// one of them at infinity, whether the ray from the other in its direction leaves the scene.
// Counts the ray.
bool connectVertices(const MutationContext& context, const PathVertex& a, const PathVertex& b);

// Lens subpath of x: the index m of the first vertex, counting from the camera, that is not
// specular (x_m is then followed by specular vertices x_{m+1} .. x_{k-1} and the camera).
int firstNonSpecularFromCamera(const Scene& scene, const Path& x);
// Whether the Dirac lobe at specular vertex x_i is a reflection (its neighbours on one side).
bool isReflection(const Path& x, int i);
// Direction from vertex `at` (arriving from `from`) through its Dirac lobe of the given kind;
// false where the lobe does not exist (total internal reflection) or the sides disagree.
bool specularBounce(const Scene& scene, const PathVertex& at, const Vec3f& from, bool reflection,
                    Vec3f* w);
// log of a direction density p(theta) / (2 pi sin theta) for theta log-uniform in
// [theta1, theta2]: Veach's exponential perturbation of a direction (1997, 11.4.3); -infinity
// outside the range.
double logAnglePerturbationDensity(double theta, double theta1, double theta2);
// Samples a direction at angle theta (log-uniform in [theta1, theta2]) around w.
Vec3f perturbDirection(const Vec3f& w, double theta1, double theta2, Rng& rng);
// The same on the film: an offset of log-uniform length in [r1, r2] pixels; the density per
// square pixel, p(r) / (2 pi r).
double logFilmPerturbationDensity(double r, double r1, double r2);
Vec2f perturbFilm(const Vec2f& film, double r1, double r2, Rng& rng);

// The direction of the ray that reaches `to` from `from`: from the origin Scene::spawnRay gives a
// ray leaving `from` (a little off its surface), not from `from` itself. The perturbations turn
// and compare these, so that an angle sampled at one end of an edge is the angle measured there
// afterwards (over an edge of a millimetre the two origins differ by a tenth of a radian).
Vec3f tracedDirection(const Scene& scene, const PathVertex& from, const PathVertex& to);
// The same towards a point: the direction that makes a ray leaving `from` pass through it.
Vec3f aimedDirection(const Scene& scene, const PathVertex& from, const Vec3f& point);

// A light vertex as BDPT starts its light subpaths (Path's densities are BDPT's): light
// `uPick` picks by power, then a point light's position, a point of an area light by area (u),
// or the environment's vertex at infinity, its direction by the map's importance (u[0], u[1]).
// False for a scene without lights.
bool sampleLightVertex(const Scene& scene, float uPick, const float u[3], PathVertex* v);

// The first vertex of a light subpath from the environment vertex x0: a point of the disk of
// the bounding sphere's radius that faces x0's direction (u, uniformly: density
// Lights::environmentDiskDensity), and the surface the ray from it along x0's light hits. False
// when it misses the scene.
bool traceFromEnvironment(const MutationContext& context, const PathVertex& x0, const Vec2f& u,
                          PathVertex* hit);

// Angle between two unit vectors, accurate for small angles.
double angleBetween(const Vec3f& a, const Vec3f& b);

// Follows x's specular chain from a new first direction: starting at y[from] (already set),
// stepping towards `to` (to < from: towards the light; to > from: towards the camera), traces
// through the vertices that replace x's specular vertices strictly between `from` and `to`,
// each through the same kind of lobe (reflection or refraction) as in x, and ends at the vertex
// that replaces x[to], which must not be specular. y must have x's length. False when a ray
// misses, meets a surface of another kind, or a lobe does not exist.
bool followSpecularChain(const MutationContext& context, const Path& x, Path* y, int from, int to,
                         const Vec3f& firstDirection);

// Veach's perturbation sizes (1997, 11.4.3; Mitsuba's defaults): film offsets from r1 = 0.1
// pixel to r2, the radius of a disc covering a tenth of the image; direction perturbations over
// the angles those offsets subtend from the camera.
struct PerturbationSizes {
  double r1 = 0, r2 = 0;          // pixels
  double theta1 = 0, theta2 = 0;  // radians
};
PerturbationSizes perturbationSizes(const Camera& camera);

}  // namespace farm
