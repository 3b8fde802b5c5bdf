#pragma once
// Unidirectional path tracing with next-event estimation, the two strategies combined by the
// power heuristic (Veach 1997, ch. 9). The reference estimator the others are checked against.
#include <cstdint>
#include <functional>
#include <vector>

#include "common/film/splat_buffer.h"
#include "common/sampling/sampler.h"
#include "common/scene/scene.h"
#include "common/transport/path.h"
#include "common/transport/path_vertex.h"

namespace farm {

class PathTracer {
 public:
  // maxDepth: longest path in edges (-1: unbounded, Russian roulette ends paths).
  PathTracer(const Scene& scene, int maxDepth);

  // Radiance arriving at the camera along r.
  Spectrum radiance(const Ray& r, Sampler& sampler) const;
  // The camera ray through `film`: from a thin lens's point (two samples of the camera stream)
  // or the pinhole.
  Ray primaryRay(const Vec2f& film, Sampler& sampler) const;
  // One camera sample at `film`: appends the splat A_px * L (see Camera).
  void sample(const Vec2f& film, Sampler& sampler, std::vector<Splat>* splats) const;

  // The paths one camera sample at `film` builds, each with its MIS-weighted value as its splat
  // would carry it (A_px * the radiance it adds): those that hit a light, and those completed by
  // next-event estimation. Each path is the light vertex of next-event estimation (none when the
  // camera's subpath hit the light itself) followed by camera[0 .. count-1], the camera's
  // subpath from its far end back to the camera. The sum of the values is sample()'s splat;
  // ERPT seeds its chains with these paths.
  struct TracedPath {
    const PathVertex* light;   // nullptr when camera[0] lies on a light
    const PathVertex* camera;  // camera[count - 1] is the camera
    int count;
    Spectrum value;
    // The path in Path's order (the light's end first), into *x: what a chain seeded with this
    // sample starts from.
    void assignTo(Path* x) const;
  };
  void visitPaths(const Vec2f& film, Sampler& sampler,
                  const std::function<void(const TracedPath&)>& visit) const;

  uint64_t rays() const { return rays_; }  // rays traced by this instance (one thread)

 private:
  // The walk behind radiance() and visitPaths(): calls add(value, lightVertex) for each
  // contribution, with the camera-side vertices in *vertices when it is not null.
  template <typename Add>
  void walk(const Ray& primary, Sampler& sampler, std::vector<PathVertex>* vertices,
            const Add& add) const;
  // Next-event estimation from a path vertex at p (n: its geometric normal; 0 in a medium):
  // picks a light and a point (or direction) of it, weights by the transmittance to it and the
  // power heuristic against the vertex's own sampling. scatter(wi, &f, &pdf, &medium) gives the
  // vertex's value towards world direction wi (the BSDF times the cosine, or the phase
  // function), the density its own sampling has for wi, and the medium a ray towards wi starts
  // in; false where wi is unusable. record: pass add the light vertex (visitPaths).
  template <typename Scatter, typename Add>
  void nextEvent(const Vec3f& p, const Vec3f& n, const Spectrum& beta, const float uLight[4],
                 Sampler& sampler, const Scatter& scatter, bool record, const Add& add) const;

  const Scene& scene_;
  int maxDepth_;
  mutable uint64_t rays_ = 0;
};

// Russian roulette survival probability from the path throughput's largest channel ratio.
inline float russianRouletteSurvival(float throughputScale) {
  return std::min(0.95f, std::max(throughputScale, 0.05f));
}
constexpr int kRussianRouletteDepth = 5;  // vertices before roulette starts
constexpr int kUnboundedDepth = 1 << 12;  // a safety cap on path length when maxDepth is -1

// The roulette of Scene::survivalBeyondReach at a medium vertex at p: false when the path ends
// there; otherwise *beta is divided by the chance it survived with. Within the reach the chance
// is 1 and no number is drawn.
inline bool survivesBeyondReach(const Scene& scene, const Vec3f& p, Sampler& sampler,
                                SampleStream stream, Spectrum* beta) {
  const float q = scene.survivalBeyondReach(p);
  if (q >= 1) return true;
  if (sampler.next(stream) >= q) return false;
  *beta /= q;
  return true;
}

}  // namespace farm
