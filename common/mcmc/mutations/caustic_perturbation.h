#pragma once
// The caustic perturbation (Veach 1997, 11.4.3.2): for paths that end (L|D) S* D E, seen by the
// camera at a non-specular vertex x_{k-1} lit through a specular chain from x_m, turn the
// direction leaving x_m by a small angle (log-uniform between theta1 and theta2, scaled by the
// ratio of the camera's edge to the chain's length, as Veach proposes, so that the image moves
// about as much as under a lens perturbation), retrace the chain with the same lobes, and join
// the new x_{k-1} to the camera. It follows caustics, which the lens perturbation cannot: their
// paths cannot be joined on the camera side of the specular chain.
//
// T(y | x) = p(angle) / (2 pi sin(angle)) * the area conversions along the retraced vertices,
// times the Dirac lobes' solid-angle ratios (the chain is traced from the light side). The
// angle's range depends on the path it starts from, so each direction checks its own.
#include "common/mcmc/mutations/mutation.h"

namespace farm {

class CausticPerturbation final : public Mutation {
 public:
  CausticPerturbation(const MutationContext& context);
  MutationType type() const override { return MutationType::CausticPerturbation; }
  bool appliesTo(const Path& x) const override;
  bool propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const override;
  double logDensity(const Path& from, const Path& to, const MutationRecord& record) const override;

 private:
  double angleScale(const Path& x, int m) const;
  PerturbationSizes sizes_;
};

}  // namespace farm
