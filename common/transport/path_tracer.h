#pragma once
// Unidirectional path tracing with next-event estimation, the two strategies combined by the
// power heuristic (Veach 1997, ch. 9). The reference estimator the others are checked against.
#include <cstdint>
#include <vector>

#include "common/film/splat_buffer.h"
#include "common/scene/scene.h"
#include "common/transport/sampler.h"

namespace farm {

class PathTracer {
 public:
  // maxDepth: longest path in edges (-1: unbounded, Russian roulette ends paths).
  PathTracer(const Scene& scene, int maxDepth);

  // Radiance arriving at the camera along r.
  Spectrum radiance(const Ray& r, Sampler& sampler) const;
  // One camera sample at `film`: appends the splat A_px * L (see Camera).
  void sample(const Vec2f& film, Sampler& sampler, std::vector<Splat>* splats) const;

  uint64_t rays() const { return rays_; }  // rays traced by this instance (one thread)

 private:
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

}  // namespace farm
