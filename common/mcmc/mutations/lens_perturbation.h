#pragma once
// The lens perturbation (Veach 1997, 11.4.3.1): for paths whose lens subpath E S* D (or E S* L)
// meets a vertex joinable to the rest, move the film point by a small offset (log-uniform length
// between r1 and r2 pixels, uniform angle), retrace the camera ray through the same specular
// lobes, and join the new non-specular vertex to the unchanged x_{m-1} (or, for E S* L, land on
// the light again). Small steps over the image: what makes MLT's images smooth where it is bright.
//
// T(y | x) = p(film offset) * (A_px We: the film-to-direction Jacobian of the camera) * the area
// conversions along the retraced vertices; the offset's density depends on its length only, so
// it is the same both ways, but the rest is evaluated on each path.
#include "common/mcmc/mutations/mutation.h"

namespace farm {

class LensPerturbation final : public Mutation {
 public:
  LensPerturbation(const MutationContext& context);
  MutationType type() const override { return MutationType::LensPerturbation; }
  bool appliesTo(const Path& x) const override;
  bool propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const override;
  double logDensity(const Path& from, const Path& to, const MutationRecord& record) const override;

 private:
  PerturbationSizes sizes_;
};

// The density of the lens part shared with the multi-chain perturbation: the film offset between
// the two paths' film points, the camera's Jacobian and the conversions from the camera down to
// to[m]. -infinity when it cannot be.
double logLensChainDensity(const MutationContext& context, const PerturbationSizes& sizes,
                           const Path& from, const Path& to, int m);
// Retraces the lens chain of x (camera .. x_m) from a perturbed film point into y (x's length).
bool perturbLensChain(const MutationContext& context, const PerturbationSizes& sizes, const Path& x,
                      int m, Rng& rng, Path* y);

}  // namespace farm
