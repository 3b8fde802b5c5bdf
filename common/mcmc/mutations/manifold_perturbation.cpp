#include "common/mcmc/mutations/manifold_perturbation.h"

#include <cmath>

#include "common/mcmc/mutations/lens_perturbation.h"
#include "common/scene/scene.h"
#include "common/transport/specular_manifold.h"

namespace farm {

ManifoldPerturbation::ManifoldPerturbation(const MutationContext& context)
    : Mutation(context), sizes_(perturbationSizes(context.scene.camera())) {}

bool ManifoldPerturbation::chainOf(const Path& x, int* e, int* m) const {
  const Scene& scene = context_.scene;
  if (x.vertices.size() < 4) return false;
  *m = firstNonSpecularFromCamera(scene, x);
  if (*m < 2 || !x.isSpecular(scene, *m - 1)) return false;
  *e = *m - 1;
  while (*e > 0 && x.isSpecular(scene, *e)) --*e;
  // (A chain from the environment has no point at its start for the walk to hold.)
  return !atInfinity(x[*e]) && isSpecularChain(scene, x, *e, *m);
}

bool ManifoldPerturbation::appliesTo(const Path& x) const {
  int e, m;
  return chainOf(x, &e, &m);
}

bool ManifoldPerturbation::propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const {
  int e, m;
  const int k = x.length();
  if (!chainOf(x, &e, &m)) return false;
  *record = {MutationType::ManifoldPerturbation, e + 1, 1, k - 1 - e, k - 1 - e};
  Path lens;
  if (!perturbLensChain(context_, sizes_, x, m, rng, &lens)) return false;
  if (!manifoldWalk(context_, x, e, m, lens[m], y, &stats_)) return false;
  for (int i = m + 1; i <= k; ++i) (*y)[i] = lens[i];
  Path back;
  if (!manifoldWalk(context_, *y, e, m, x[m], &back, &stats_) ||
      !sameSpecularChain(x, back, e, m, manifoldWalkTolerance(context_.scene, x[m].p))) {
    ++irreversible_;
    return false;
  }
  return true;
}

double ManifoldPerturbation::logDensity(const Path& from, const Path& to,
                                        const MutationRecord& r) const {
  int e, m, fromE, fromM;
  if (from.length() != to.length() || !chainOf(to, &e, &m) || !chainOf(from, &fromE, &fromM) ||
      e != fromE || m != fromM || r.keptLight != e + 1)
    return -INFINITY;
  const double logT = logLensChainDensity(context_, sizes_, from, to, m) +
                      logSpecularChainMeasureRatio(context_.scene, to, e, m);
  return std::isfinite(logT) ? logT : -INFINITY;
}

}  // namespace farm
