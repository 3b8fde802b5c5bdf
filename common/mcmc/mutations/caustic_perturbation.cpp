#include "common/mcmc/mutations/caustic_perturbation.h"

#include <cmath>

#include "common/scene/scene.h"

namespace farm {

namespace {

// m: the first non-specular vertex before x_{k-1}, or -1 when the path does not end (L|D) S* D E
// or its chain starts at the environment (a direction, from no point to perturb it at).
int chainStart(const Scene& scene, const Path& x) {
  const int k = x.length();
  if (k < 2 || x.isSpecular(scene, k - 1)) return -1;
  int m = k - 2;
  while (m > 0 && x.isSpecular(scene, m)) --m;
  return x.isSpecular(scene, m) || atInfinity(x[m]) ? -1 : m;
}

}  // namespace

CausticPerturbation::CausticPerturbation(const MutationContext& context)
    : Mutation(context), sizes_(perturbationSizes(context.scene.camera())) {}

double CausticPerturbation::angleScale(const Path& x, int m) const {
  // Veach (1997, p. 354): the camera's edge over the length of the chain from x_m to x_{k-1}.
  const int k = x.length();
  double chain = 0;
  for (int j = m; j < k - 1; ++j) chain += double(length(x[j + 1].p - x[j].p));
  return double(length(x[k].p - x[k - 1].p)) / chain;
}

bool CausticPerturbation::appliesTo(const Path& x) const {
  return chainStart(context_.scene, x) >= 0;
}

bool CausticPerturbation::propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const {
  const int m = chainStart(context_.scene, x);
  const int k = x.length();
  *record = {MutationType::CausticPerturbation, m + 1, 1, k - 1 - m, k - 1 - m};
  if (m < 0) return false;
  const double scale = angleScale(x, m);
  Vec3f w = perturbDirection(tracedDirection(context_.scene, x[m], x[m + 1]), sizes_.theta1 * scale,
                             std::min(sizes_.theta2 * scale, M_PI), rng);
  *y = x;
  if (!followSpecularChain(context_, x, y, m, k - 1, w)) return false;
  if (!connectVertices(context_, (*y)[k - 1], (*y)[k])) return false;
  // The angle measured back from the two paths is the one drawn, up to rounding, except where
  // the traced vertex is not where the drawn direction points (seen at a corner, two vertices
  // 0.014 apart: drawn at 0.61 rad or more, measured 0.38). There T(y|x) would read 0 and the
  // acceptance infinity: refuse such a move, which leaves the chain where it is, as any
  // proposal that fails does.
  return std::isfinite(logDensity(x, *y, *record));
}

double CausticPerturbation::logDensity(const Path& from, const Path& to,
                                       const MutationRecord& r) const {
  const Scene& scene = context_.scene;
  const int k = to.length();
  const int m = r.keptLight - 1;
  if (from.length() != k || m < 0 || chainStart(scene, to) != m || chainStart(scene, from) != m)
    return -INFINITY;
  const double scale = angleScale(from, m);
  const double theta = angleBetween(tracedDirection(scene, from[m], from[m + 1]),
                                    tracedDirection(scene, to[m], to[m + 1]));
  double logT = logAnglePerturbationDensity(theta, sizes_.theta1 * scale,
                                            std::min(sizes_.theta2 * scale, M_PI));
  for (int j = m + 1; j <= k - 1; ++j) {
    logT += std::log(geometricConversion(to[j - 1], to[j]));
    if (j < k - 1) {
      // Traced from the light side: the Dirac lobe's delta turns from the camera-side
      // direction into the light-side one (Path's convention).
      const PathVertex& v = to[j];
      Frame frame(v.ns);
      logT += std::log(
          double(scene.bsdfOf(v.shape).diracJacobian(frame.toLocal(normalize(to[j - 1].p - v.p)),
                                                     frame.toLocal(normalize(to[j + 1].p - v.p)))));
    }
  }
  return std::isfinite(logT) ? logT : -INFINITY;
}

}  // namespace farm
