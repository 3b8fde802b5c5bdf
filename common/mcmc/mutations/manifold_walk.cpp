#include "common/mcmc/mutations/manifold_walk.h"

#include <algorithm>
#include <cmath>

#include "common/scene/scene.h"
#include "common/transport/specular_manifold.h"

namespace farm {

namespace {

constexpr int kMaxSteps = 24;
constexpr double kSmallestStep = 1.0 / 1024;
// Projections (each a ray per chain vertex) a walk may spend: a walk that needs more is lost.
constexpr int kMaxProjections = 64;

// x_{a+1} .. x_b of `trial` traced from trial[a] in direction w through x's lobes, on x's shapes
// for the specular vertices.
bool project(const MutationContext& context, const Path& x, int a, int b, const Vec3f& w,
             Path* trial) {
  if (!followSpecularChain(context, x, trial, a, b, w)) return false;
  for (int i = a + 1; i < b; ++i) {
    if ((*trial)[i].shape != x[i].shape) return false;
  }
  return true;
}

}  // namespace

const char* walkLossName(WalkLoss loss) {
  switch (loss) {
    case WalkLoss::kNotAChain:
      return "walks lost: not a chain";
    case WalkLoss::kStepCap:
      return "walks lost: step cap";
    case WalkLoss::kSingularDerivative:
      return "walks lost: singular derivative";
    case WalkLoss::kProjectionCap:
      return "walks lost: projection cap";
    case WalkLoss::kStepVanished:
      return "walks lost: step vanished";
    case WalkLoss::kEndBlocked:
      return "walks lost: end blocked";
    case WalkLoss::kCount:
      break;
  }
  return "walks lost";
}

bool sameSpecularChain(const Path& a, const Path& b, int first, int last, double walkTolerance) {
  for (int i = first + 1; i < last; ++i) {
    const double edge =
        std::min(double(length(a[i].p - a[i - 1].p)), double(length(a[i + 1].p - a[i].p)));
    const double apart = std::max(1e-3 * edge, kSameSolutionTolerances * walkTolerance);
    if (a[i].shape != b[i].shape || !(double(length(b[i].p - a[i].p)) <= apart)) return false;
  }
  return true;
}

double manifoldWalkTolerance(const Scene& scene, const Vec3f& target) {
  return 1e-6 * (double(maxAbsComponent(target)) + double(scene.extent()));
}

bool manifoldWalk(const MutationContext& context, const Path& x, int a, int b,
                  const PathVertex& target, Path* y, ManifoldWalkStats* stats,
                  std::vector<double>* residuals) {
  const Scene& scene = context.scene;
  if (stats) ++stats->walks;
  auto lose = [stats](WalkLoss why) {
    if (stats) ++stats->lost[int(why)];
    return false;
  };
  if (!isSpecularChain(scene, x, a, b) || target.kind != PathVertex::Kind::Surface)
    return lose(WalkLoss::kNotAChain);
  const double tolerance = manifoldWalkTolerance(scene, target.p);
  Path current = x, trial;
  double beta = 1;
  int projections = 0;
  for (int step = 0;; ++step) {
    const Vec3f r = target.p - current[b].p;
    const double distance = double(length(r));
    if (residuals) residuals->push_back(distance);
    if (distance < tolerance) break;
    if (step == kMaxSteps) return lose(WalkLoss::kStepCap);
    if (stats) ++stats->iterations;
    // Newton: the end should move by r (in its tangent plane); x_{a+1} by the derivative times it,
    // both in the tangent bases of their geometric normals (Scene::surfaceDifferential's).
    Matrix2 d;
    if (!specularChainDerivative(scene, current, a, b, true, &d))
      return lose(WalkLoss::kSingularDerivative);
    const Frame end(current[b].n), first(current[a + 1].n);
    const double du = dot(r, end.s), dv = dot(r, end.t);
    const double su = d.m[0][0] * du + d.m[0][1] * dv, sv = d.m[1][0] * du + d.m[1][1] * dv;
    bool moved = false;
    while (!moved) {
      const Vec3f q = current[a + 1].p + first.s * float(beta * su) + first.t * float(beta * sv);
      if (++projections > kMaxProjections) return lose(WalkLoss::kProjectionCap);
      trial = current;  // into trial's own storage: a walk allocates its two paths once
      // Aimed from where the ray leaves x_a (a little off its surface), so that it meets x_{a+1}'s
      // surface at q itself: aimed from x_a, it would land a little beside q, the same little
      // every step, and the walk would stall there.
      const Vec3f w = aimedDirection(scene, current[a], q);
      if (project(context, x, a, b, w, &trial) &&
          double(length(target.p - trial[b].p)) < distance) {
        std::swap(current, trial);
        beta = std::min(1.0, 2 * beta);
        moved = true;
      } else {
        if (stats) ++stats->halvings;
        beta *= 0.5;
        if (beta < kSmallestStep) return lose(WalkLoss::kStepVanished);
      }
    }
  }
  // The chain ends at the target itself, which it reaches unoccluded.
  current[b] = target;
  if (!connectVertices(context, current[b - 1], current[b])) return lose(WalkLoss::kEndBlocked);
  if (stats) ++stats->converged;
  *y = std::move(current);
  return true;
}

}  // namespace farm
