#include "common/mcmc/mutations/lens_perturbation.h"

#include <cmath>
#include <vector>

#include "common/scene/scene.h"

namespace farm {

namespace {

// x_m, the first non-specular vertex from the camera, can be joined to what comes before it:
// x_{m-1} is not specular, or x_m is the light itself (not the environment, whose direction
// no perturbed ray traces to).
bool joinable(const Scene& scene, const Path& x, int m) {
  if (m == 0) return x[0].light >= 0 && !atInfinity(x[0]);
  return !x.isSpecular(scene, m - 1);
}

bool filmPoint(const Camera& camera, const Path& x, Vec2f* film) {
  const int k = x.length();
  return camera.project(x[k].p, normalize(x[k - 1].p - x[k].p), film);
}

}  // namespace

LensPerturbation::LensPerturbation(const MutationContext& context)
    : Mutation(context), sizes_(perturbationSizes(context.scene.camera())) {}

bool LensPerturbation::appliesTo(const Path& x) const {
  if (x.vertices.size() < 2) return false;
  const int m = firstNonSpecularFromCamera(context_.scene, x);
  return joinable(context_.scene, x, m);
}

bool perturbLensChain(const MutationContext& context, const PerturbationSizes& sizes, const Path& x,
                      int m, Rng& rng, Path* y) {
  const Camera& camera = context.scene.camera();
  Vec2f film;
  if (!filmPoint(camera, x, &film)) return false;
  Vec2f moved = perturbFilm(film, sizes.r1, sizes.r2, rng);
  if (!(moved.x >= 0 && moved.y >= 0 && moved.x < camera.width() && moved.y < camera.height()))
    return false;
  *y = x;
  const int k = x.length();
  return followSpecularChain(context, x, y, k, m, camera.generateRay(moved, x[k].p).d);
}

bool LensPerturbation::propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const {
  const int m = firstNonSpecularFromCamera(context_.scene, x);
  const int n = int(x.vertices.size());
  *record = {MutationType::LensPerturbation, m, 1, n - 1 - m, n - 1 - m};
  if (!perturbLensChain(context_, sizes_, x, m, rng, y)) return false;
  if (m == 0) return (*y)[0].light >= 0;
  return connectVertices(context_, (*y)[m - 1], (*y)[m]);
}

double logLensChainDensity(const MutationContext& context, const PerturbationSizes& sizes,
                           const Path& from, const Path& to, int m) {
  const Scene& scene = context.scene;
  const Camera& camera = scene.camera();
  const int k = to.length();
  Vec2f a, b;
  if (!filmPoint(camera, from, &a) || !filmPoint(camera, to, &b)) return -INFINITY;
  const double r = std::hypot(double(b.x) - a.x, double(b.y) - a.y);
  double logT = logFilmPerturbationDensity(r, sizes.r1, sizes.r2);
  // Film to direction: a uniform film point has direction density We, so a film density p
  // becomes p A_px We; then to area at to[k-1], and through each specular vertex.
  const double we = camera.importance(to[k].p, normalize(to[k - 1].p - to[k].p));
  logT += std::log(double(camera.pixelCount()) * we * geometricConversion(to[k], to[k - 1]));
  for (int j = k - 2; j >= m; --j) {
    if (!to.isSpecular(scene, j + 1)) return -INFINITY;
    logT += std::log(geometricConversion(to[j + 1], to[j]));
  }
  return std::isfinite(logT) ? logT : -INFINITY;
}

double LensPerturbation::logDensity(const Path& from, const Path& to,
                                    const MutationRecord& r) const {
  const int n = int(to.vertices.size());
  if (int(from.vertices.size()) != n || r.keptLight + r.added + 1 != n) return -INFINITY;
  const int m = r.keptLight;
  if (to.isSpecular(context_.scene, m) || !joinable(context_.scene, to, m)) return -INFINITY;
  return logLensChainDensity(context_, sizes_, from, to, m);
}

}  // namespace farm
