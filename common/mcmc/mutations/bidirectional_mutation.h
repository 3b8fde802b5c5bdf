#pragma once
// The bidirectional mutation (Veach 1997, 11.4.2): delete a run of vertices of any length
// (possibly none, possibly the light vertex, the camera only where it is a thin lens's point),
// then grow a new run of any length (possibly none) from both ends, s' vertices from the light
// side and t' from the camera side, and join the two ends with one connecting edge. The only
// mutation that can change the path's length and reach any path: the one that keeps the chain
// ergodic.
//
// Discrete choices, each with its probability in T:
//   removed vertices nd in [0, n - 1] with weight 2^-nd (short deletions first), and through a
//   thin lens also nd = n (the whole path regrown);
//   the start of the deleted run uniformly among its n - nd positions, and through a thin lens
//   among n - nd + 1 when nd > 0: the extra one deletes the camera's end of the path, whose
//   regrown camera side then starts from a new lens point (Camera::lensPoint, uniform). Without
//   it the lens point a chain's seed had would never move. The lens is measured by the share of
//   its area, in which a uniform lens point has density 1 (Path's contribution is per that
//   measure, camera.h), so the new point adds no factor to T;
//   added vertices na with weight 2^-|na - nd| within |na - nd| <= 4 (the length stays near
//   the current one), never both zero, and the new path within the maximum depth;
//   the split s' + t' = na uniformly.
// T(y | x) sums over the splits, each the product of the new vertices' densities from their
// side (every split that could have built y counts, as in Veach's formulation).
#include "common/mcmc/mutations/mutation.h"

namespace farm {

class BidirectionalMutation final : public Mutation {
 public:
  using Mutation::Mutation;
  MutationType type() const override { return MutationType::Bidirectional; }
  bool appliesTo(const Path& x) const override;
  bool propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const override;
  double logDensity(const Path& from, const Path& to, const MutationRecord& record) const override;

  static constexpr int kMaxLengthChange = 4;
};

}  // namespace farm
