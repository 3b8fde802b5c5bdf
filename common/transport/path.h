#pragma once
// A light path in Veach's path space (Veach 1997, ch. 8): vertices x_0 .. x_k, x_0 on a light and
// x_k the (pinhole) camera. BDPT builds its subpaths from the same PathVertex; a BDPT sample's
// strategy (s, t) is the path of the light subpath's first s vertices followed by the camera
// subpath's first t in reverse. The path-space mutations edit it, and its serialized form is a
// path-space chain's state, so that the chain resumes exactly on another host.
//
// The measurement contribution is in the radiance form that BDPT estimates:
//   f(x) = Le(x_0 -> x_1) G(x_0, x_1) prod_{i=1}^{k-1} f_s(x_{i+1} <- x_i <- x_{i-1}) G(x_i,
//   x_{i+1})
// with the camera's edge carrying A_px We (see Camera), G(x_i, x_{i+1}) = |ng_i . w| |ns_{i+1} . w|
// / d^2 (the sender's geometric cosine, the receiver's shading cosine; the camera has none), and
// at a vertex whose BSDF is a Dirac lobe the coefficient of the delta function in place of f_s
// (its Fresnel value divided by |ns . w|): the contribution with respect to the measure in which
// specular vertices are still area-measured (Veach 1997, 8.3.2). Transition densities of the
// mutations use the same convention, so the deltas cancel in every acceptance ratio.
#include <cmath>
#include <string>
#include <vector>

#include "common/sampling/rng.h"
#include "common/scene/scene.h"
#include "common/transport/path_vertex.h"

namespace farm {

// How Path::contribution estimates the transmittance of edges through density grids
// (homogeneous media are exact): the mean of `samples` ratio-tracking estimates with numbers
// from rng, a non-negative unbiased estimate (pseudo-marginal MLT, Kronander et al. 2015,
// section 3.3), or, with marchSteps > 0, ray marching (deterministic, biased by its step);
// marchSteps < 0: none at all (see kCarriesLightCheck).
struct TransmittanceEstimator {
  Rng* rng = nullptr;
  int samples = 1;
  int marchSteps = 0;
};
// The estimator of a contribution given none: marching, fine enough for a grid of 256 cells
// along a ray, so that whether a path carries light is a property of the path alone.
constexpr int kDefaultMarchSteps = 1024;
// For checks of a path that its builder saw unblocked and need no value (whether it projects
// onto the film, its lobes exist, ...): marchSteps < 0 leaves the transmittances out (each
// vertex in a medium takes the medium it names), and no ray is traced.
inline const TransmittanceEstimator kCarriesLightCheck{nullptr, 1, -1};

// The media along a path's edges, walked from the camera (in the medium the scene puts it)
// towards the light as Scene::mediumSegments walks them. Edge i joins x_i and x_{i+1}: it
// leaves x_{i+1} in medium `from` and reaches x_i in medium `to`, its stretches in media
// ordered from x_{i+1}.
struct PathMedia {
  struct Edge {
    int from = -1, to = -1;
    std::vector<MediumSegment> segments;
  };
  std::vector<Edge> edges;
  // The medium around x_i (on the side of its edge towards the camera), -1 for vacuum.
  int around(const Scene& scene, int i) const {
    return i == int(edges.size()) ? scene.cameraMedium() : edges[size_t(i)].to;
  }
};

struct PathContribution {
  // log of the luminance of f(x); -infinity when f(x) = 0 (or the path is not one the target
  // allows: longer than the maximum depth, outside the film, on the wrong side of a surface).
  double logLuminance = -INFINITY;
  Spectrum color;  // f(x) / luminance(f(x)): the splat of one unit of luminance
  Vec2f film;      // where x_{k-1} projects, in pixels
  bool carriesLight() const { return std::isfinite(logLuminance); }
};

class Path {
 public:
  std::vector<PathVertex> vertices;  // x_0 (light) .. x_k (camera)

  int length() const { return int(vertices.size()) - 1; }  // edges
  const PathVertex& operator[](int i) const { return vertices[size_t(i)]; }
  PathVertex& operator[](int i) { return vertices[size_t(i)]; }

  // Strategy (s, t) of BDPT: light[0 .. s-1] then camera[t-1 .. 0].
  static Path fromSubpaths(const PathVertex* light, int s, const PathVertex* camera, int t);

  // f(x) as above, in a form that neither overflows nor underflows (a running product
  // renormalized at every factor). Does not test visibility: whoever builds an edge tests it.
  // maxDepth: longest path in edges the target allows (< 0: unbounded).
  // In a scene with media, the edges' transmittances (through null boundaries) and the vertices
  // in media (sigma_s times the phase function, no cosines) enter f, the grids' by `estimator`
  // (nullptr: kDefaultMarchSteps of marching).
  PathContribution contribution(const Scene& scene, int maxDepth,
                                const TransmittanceEstimator* estimator = nullptr) const;

  // The media along the edges (see PathMedia); false when an edge is blocked or a vertex in a
  // medium lies outside every medium.
  bool media(const Scene& scene, PathMedia* out) const;
  // The density of the free flight (Medium::sampleFreeFlight, through every medium on the way)
  // that puts x_j where it is, flying from its neighbour towards the light (fromLight: x_{j-1})
  // or towards the camera (x_{j+1}): the probability of passing the media, times the landing
  // density where x_j lies in a medium. 1 along an edge without media.
  double freeFlightDensity(const Scene& scene, const PathMedia& media, int j, bool fromLight) const;

  // Whether x_i scatters only through Dirac lobes (a specular vertex).
  bool isSpecular(const Scene& scene, int i) const;
  // Whether x is an area light seen directly: the path L E (seen_emission.h).
  bool isSeenEmission(const Scene& scene) const;

  // The area densities of each vertex sampled from the light side (pL) and from the camera side
  // (pE), from the vertices alone (see pathDensities); at a vertex sampled through a Dirac lobe
  // the lobe's selection probability times the geometric factor (the delta convention above).
  void densities(const Scene& scene, double* pL, double* pE, char* delta) const;

  // A compact, exact byte form (floats bit for bit) and its inverse; deserialize() checks the
  // bytes against the scene (vertex kinds, shape and light indices, finite coordinates) and
  // returns false for anything that is not a path of this scene.
  std::string serialize() const;
  bool deserialize(const std::string& bytes, const Scene& scene);
};

// The cosine of w at the receiving side of an edge into `to` over the squared distance: the
// factor that turns a solid-angle density (or a perturbed direction) at the sender into an area
// density at `to` (1 / d^2 at the camera).
double geometricConversion(const PathVertex& from, const PathVertex& to);

}  // namespace farm
