#pragma once
// The area lights the camera sees directly: the paths L E (Path::isSeenEmission), estimated by
// two strategies weighted by the power heuristic (Veach 1997, 9.2): a film point whose ray hits
// a light, and a point of a light projected onto the film (BDPT's strategy t = 1).
//
// Path-space MLT leaves these paths to this estimator rather than to its chains. Where a small
// light is in view (the water caustic's: 6 pixels carry 59% of the image's luminance), the
// chains' share on it is set by how many of them the bootstrap happens to start there, a
// binomial draw that left the rest of the image 16-32% too dark at 30 s with 64 chains
// (measured: docs/conventions.md, "Lights in view, apart from mlt's chains"), and the chains spent
// most of their mutations there. Here those pixels cost two rays a sample, and a light smaller than
// a pixel, which a film point hits a few times in a million, is found every time by its points.
//
// Lights seen through specular surfaces (L S+ E) stay with the chains: there only the film
// point can find them, and a small light's reflection in a mirror is as rare for it as the
// light itself, while the chains' perturbations keep such paths once they have them.
#include <cstdint>
#include <vector>

#include "common/film/splat_buffer.h"
#include "common/math/vec.h"
#include "common/sampling/rng.h"
#include "common/scene/scene.h"

namespace farm {

class SeenEmission {
 public:
  explicit SeenEmission(const Scene& scene);

  // Whether path-space MLT renders the paths L E here rather than in its chains: in scenes
  // without media (through media an edge carries a transmittance estimate, which the chains'
  // own paths handle and this estimator does not), seen through a pinhole (this estimator
  // projects through the camera's point, not through a lens).
  static bool separates(const Scene& scene);

  // One sample: the film point `film` (pixels) and a light point from `rng`; appends their
  // splats (A_px times the radiance they carry, see Camera) to *splats.
  void sample(const Vec2f& film, Rng& rng, std::vector<Splat>* splats) const;

  uint64_t rays() const { return rays_; }

 private:
  // The area densities at a point y of area light `light` (normal n) with which the two
  // strategies find the path y -> camera: through the film, and as the light's point.
  void densities(int light, const Vec3f& y, const Vec3f& n, double* film, double* lightPoint) const;

  const Scene& scene_;
  mutable uint64_t rays_ = 0;
};

}  // namespace farm
