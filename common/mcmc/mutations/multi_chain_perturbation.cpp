#include "common/mcmc/mutations/multi_chain_perturbation.h"

#include <cmath>

#include "common/mcmc/mutations/lens_perturbation.h"
#include "common/scene/scene.h"

namespace farm {

namespace {

// The next non-specular vertex below x_c (x_{j+1} .. x_{c-1} specular).
int nextNonSpecular(const Scene& scene, const Path& x, int c) {
  int j = c - 1;
  while (j > 0 && x.isSpecular(scene, j)) --j;
  return j;
}

}  // namespace

MultiChainPerturbation::MultiChainPerturbation(const MutationContext& context)
    : Mutation(context), sizes_(perturbationSizes(context.scene.camera())) {}

bool MultiChainPerturbation::appliesTo(const Path& x) const {
  if (x.vertices.size() < 3) return false;
  const int m = firstNonSpecularFromCamera(context_.scene, x);
  return m >= 1 && x.isSpecular(context_.scene, m - 1);
}

bool MultiChainPerturbation::propose(const Path& x, Rng& rng, Path* y,
                                     MutationRecord* record) const {
  const Scene& scene = context_.scene;
  const int n = int(x.vertices.size());
  const int m = firstNonSpecularFromCamera(scene, x);
  if (!perturbLensChain(context_, sizes_, x, m, rng, y)) return false;
  for (int c = m;;) {
    const int j = nextNonSpecular(scene, x, c);
    if (atInfinity(x[j])) return false;  // no traced ray ends on the environment's direction
    Vec3f w =
        perturbDirection(tracedDirection(scene, x[c], x[c - 1]), sizes_.theta1, sizes_.theta2, rng);
    if (!followSpecularChain(context_, x, y, c, j, w)) return false;
    if (j == 0 || !x.isSpecular(scene, j - 1)) {
      *record = {MutationType::MultiChainPerturbation, j, 1, n - 1 - j, n - 1 - j};
      if (j == 0) return (*y)[0].light >= 0;
      return connectVertices(context_, (*y)[j - 1], (*y)[j]);
    }
    c = j;
  }
}

double MultiChainPerturbation::logDensity(const Path& from, const Path& to,
                                          const MutationRecord& r) const {
  const Scene& scene = context_.scene;
  const int n = int(to.vertices.size());
  if (int(from.vertices.size()) != n) return -INFINITY;
  const int m = firstNonSpecularFromCamera(scene, to);
  if (m != firstNonSpecularFromCamera(scene, from) || m < 1 || !to.isSpecular(scene, m - 1))
    return -INFINITY;
  double logT = logLensChainDensity(context_, sizes_, from, to, m);
  for (int c = m;;) {
    const int j = nextNonSpecular(scene, to, c);
    if (j != nextNonSpecular(scene, from, c) || to.isSpecular(scene, j)) return -INFINITY;
    const double theta = angleBetween(tracedDirection(scene, from[c], from[c - 1]),
                                      tracedDirection(scene, to[c], to[c - 1]));
    logT += logAnglePerturbationDensity(theta, sizes_.theta1, sizes_.theta2);
    for (int i = c - 1; i >= j; --i) logT += std::log(geometricConversion(to[i + 1], to[i]));
    if (j == 0 || !to.isSpecular(scene, j - 1)) {
      if (j != r.keptLight) return -INFINITY;
      break;
    }
    c = j;
  }
  return std::isfinite(logT) ? logT : -INFINITY;
}

}  // namespace farm
