#pragma once
// The manifold perturbation (Jakob and Marschner 2012, section 5), in the form that reaches what
// Veach's perturbations cannot: a path whose lens subpath E S* D meets, below its first
// non-specular vertex x_m, a specular chain x_m S+ x_e that ends at a non-specular x_e (a
// diffuse surface or the light): a scene seen through water and lit through it (L S D S E).
// The film point moves as in the lens perturbation and the camera ray is retraced through the
// same specular lobes to the new x_m; then the manifold walk (manifold_walk.h) moves the chain
// x_{e+1} .. x_{m-1} so that it joins the unchanged x_e to the new x_m. Veach's lens
// perturbation would need x_{m-1} to be joinable; here it is specular.
//
// The walk is deterministic, so y is a function of the new x_m, and the move is reversible when
// the walk from y towards x_m finds x's own chain; a proposal whose reverse walk ends elsewhere
// (another solution of the constraints) is refused, which keeps the kernel's support symmetric.
// T(y | x) = (the lens perturbation's density of y_m, in Path's convention through the lens
// chain) * (logSpecularChainMeasureRatio of y's chain x_e .. x_m): the walk places the chain, so
// its vertices carry the generalized geometry term in place of sampled densities.
#include "common/mcmc/mutations/manifold_walk.h"
#include "common/mcmc/mutations/mutation.h"

namespace farm {

class ManifoldPerturbation final : public Mutation {
 public:
  ManifoldPerturbation(const MutationContext& context);
  MutationType type() const override { return MutationType::ManifoldPerturbation; }
  bool appliesTo(const Path& x) const override;
  bool propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const override;
  double logDensity(const Path& from, const Path& to, const MutationRecord& record) const override;

  // The walks this mutation ran (forward and reverse), and the proposals refused because the
  // reverse walk found another chain.
  const ManifoldWalkStats& walkStats() const { return stats_; }
  uint64_t irreversible() const { return irreversible_; }

 private:
  // x_e and x_m of x's chain, or false when x has none.
  bool chainOf(const Path& x, int* e, int* m) const;

  PerturbationSizes sizes_;
  mutable ManifoldWalkStats stats_;
  mutable uint64_t irreversible_ = 0;
};

}  // namespace farm
