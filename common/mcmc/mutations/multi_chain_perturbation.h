#pragma once
// The multi-chain perturbation (Veach 1997, 11.4.3.3): for paths whose lens subpath E S* D
// cannot be joined to the rest because the vertex before its non-specular end is specular too,
// as in E S D S L, a caustic seen through glass or water. A lens perturbation moves the film
// point and retraces the lens chain to the first non-specular vertex; from there the direction
// towards the light is turned by a small angle (log-uniform in [theta1, theta2]) around the
// old one, and the next specular chain is retraced, until a non-specular vertex is reached that
// can be joined to an unchanged one, or the light.
//
// T(y | x) = the lens part (see LensPerturbation) times, at each turned vertex, p(angle) /
// (2 pi sin(angle)) and the area conversions of the chain it retraced (traced from the camera
// side: no lobe ratios).
#include "common/mcmc/mutations/mutation.h"

namespace farm {

class MultiChainPerturbation final : public Mutation {
 public:
  MultiChainPerturbation(const MutationContext& context);
  MutationType type() const override { return MutationType::MultiChainPerturbation; }
  bool appliesTo(const Path& x) const override;
  bool propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const override;
  double logDensity(const Path& from, const Path& to, const MutationRecord& record) const override;

 private:
  PerturbationSizes sizes_;
};

}  // namespace farm
