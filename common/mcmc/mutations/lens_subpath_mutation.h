#pragma once
// The lens subpath mutation (Veach 1997, 11.4.4): replace the lens subpath, the camera and the
// specular vertices in front of it up to the first non-specular vertex x_m, with a new one from
// a fresh film point (uniform over the image; through a thin lens from a fresh lens point,
// uniform on the lens), sampling the Dirac lobes it meets, and connect
// its new non-specular end to x_{m-1}. When x_m is the light (the light seen through glass or
// directly), the new lens subpath must end on a light too. It moves the path across the image,
// which the perturbations do only locally.
//
// T(y | x) is the product of the new vertices' densities from the camera side (the first from
// the camera's importance, which is the density of a uniform film point); the walk's rule of
// stopping at the first non-specular vertex is decided by the vertices, so it adds no factor.
#include "common/mcmc/mutations/mutation.h"

namespace farm {

class LensSubpathMutation final : public Mutation {
 public:
  using Mutation::Mutation;
  MutationType type() const override { return MutationType::LensSubpath; }
  bool appliesTo(const Path& x) const override;
  bool propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const override;
  double logDensity(const Path& from, const Path& to, const MutationRecord& record) const override;

  static constexpr int kMaxSpecularChain = 64;  // specular vertices a new lens subpath may cross
};

}  // namespace farm
