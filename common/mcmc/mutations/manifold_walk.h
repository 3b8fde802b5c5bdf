#pragma once
// The manifold walk (Jakob and Marschner 2012, section 4.2): moves the end x_b of a specular
// chain x_a .. x_b (x_a held, x_{a+1} .. x_{b-1} specular) to a target point while the chain
// stays on its specular manifold. Each Newton step takes the derivative of x_{a+1} with respect
// to x_b (specular_manifold.h), moves x_{a+1} in its tangent plane by the step the target calls
// for, and projects back onto the manifold by ray tracing from x_a through the new x_{a+1} and
// each specular vertex's lobe (reflection or refraction, as in x) to where the chain now ends.
// A projection that misses, meets another shape or does not come closer halves the step.
#include <cstdint>
#include <vector>

#include "common/mcmc/mutations/mutation.h"

namespace farm {

// Why a walk was lost, by where it stopped (issue 43: near index 1 a curved surface's constraint
// nearly degenerates, and a high index turns projections back by total internal reflection,
// which shows as steps halved away or projections spent).
enum class WalkLoss {
  kNotAChain,           // x_a .. x_b is not a specular chain, or the target is not on a surface
  kStepCap,             // still off the target after kMaxSteps Newton steps
  kSingularDerivative,  // the chain's derivative could not be inverted
  kProjectionCap,       // the projections (a ray per chain vertex each) ran out
  kStepVanished,        // every projection missed, met another shape or came no closer
  kEndBlocked,          // the chain reached the target, which its last vertex does not see
  kCount
};
// The report's name of each, "walks lost: step cap" and so on.
const char* walkLossName(WalkLoss loss);

// What the walks did: counted, so that failures show in the report rather than vanish.
struct ManifoldWalkStats {
  uint64_t walks = 0;
  uint64_t converged = 0;
  uint64_t iterations = 0;                    // Newton steps over all walks
  uint64_t halvings = 0;                      // projections refused and retried with half the step
  uint64_t lost[int(WalkLoss::kCount)] = {};  // walks - converged, by cause
};

// y: x with x_{a+1} .. x_{b-1} moved and x_b replaced by `target` (a surface vertex), the chain
// ending within a tolerance of 1e-6 of the scene's size of it and the last segment unoccluded.
// False when the walk does not converge (in at most 24 steps and 64 projections), the chain
// cannot be followed, or the target is not reached from the chain's last vertex. residuals, when
// given, receives the distance from the chain's end to the target before each step (and the
// last, converged, one).
bool manifoldWalk(const MutationContext& context, const Path& x, int a, int b,
                  const PathVertex& target, Path* y, ManifoldWalkStats* stats = nullptr,
                  std::vector<double>* residuals = nullptr);

// Whether b's chain between x_first and x_last is a's, the same solution of the constraints: each
// inner vertex on a's shape and within a thousandth of its shorter edge in a of a's, or within
// kSameSolutionTolerances walk tolerances where that is larger (distinct solutions lie a visible
// distance apart). A walk ends within its tolerance of its target, and an ill-conditioned chain
// (vertices a millimetre apart near a caustic's fold) holds its inner vertices only to some
// times that: a thousandth of a 3 mm edge is 3 um, what the walk's end is held to, and the same
// solution found again lay 5-60 um from the first, 1-20 tolerances, on the water caustic.
constexpr double kSameSolutionTolerances = 32;
bool sameSpecularChain(const Path& a, const Path& b, int first, int last, double walkTolerance = 0);

// The tolerance within which a walk's chain ends at its target.
double manifoldWalkTolerance(const Scene& scene, const Vec3f& target);

}  // namespace farm
