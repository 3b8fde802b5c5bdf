// The specular manifold's derivatives and the manifold walk, against answers that do not come
// from the constraint code:
//  - the solid angle per unit area a chain maps between its ends, against finite differences of
//    the chain traced by the scene's own ray tracing and Dirac lobes (through a glass ball, a
//    mirror ball, a smooth-shaded refracting mesh whose normals turn across each triangle, and
//    a flat interface between media of different index), from either end;
//  - its reciprocity: eta_a^2 |cos_a| d omega_a / dA_b = eta_b^2 |cos_b| d omega_b / dA_a;
//  - the walk's solutions where they are known in closed form (a plane mirror: the point where
//    the line to the target's mirror image crosses it; a symmetric mirror ball and a ray through
//    a glass ball's centre), reached with quadratic convergence.
#include "common/mcmc/mutations/manifold_walk.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"
#include "common/transport/specular_manifold.h"

namespace farm {
namespace {

enum Bsdfs { kDiffuse, kGlass, kMirror, kWater };

SceneDescription opticsBench() {
  SceneDescription d;
  d.camera.width = d.camera.height = 16;
  BsdfDescription diffuse, glass, mirror, water;
  diffuse.twoSided = true;
  glass.type = BsdfDescription::Type::Dielectric;
  glass.intIOR = 1.5f, glass.extIOR = 1.0f;
  mirror.type = BsdfDescription::Type::Conductor;
  water.type = BsdfDescription::Type::Dielectric;
  water.intIOR = 1.33f, water.extIOR = 1.0f;
  d.bsdfs = {diffuse, glass, mirror, water};
  return d;
}

// Shapes 0 (floor, y = 0) and 1 (ceiling, y = 4) and between them a glass ball (2), a mirror
// ball (3), a smooth-shaded water patch whose vertex normals lean apart (4) and a flat one (5).
// Compact, because rays leave surfaces 1e-5 of the scene's size off them: in a large scene the
// chains the ray tracer follows differ from the ideal ones by more than the finite differences
// resolve.
SceneDescription chainScene() {
  SceneDescription d = opticsBench();
  d.shapes.push_back(quadShape(Vec3f(-4.5f, 0, -4.5f), Vec3f(0, 0, 9), Vec3f(9, 0, 0), kDiffuse));
  d.shapes.push_back(quadShape(Vec3f(-4.5f, 4, -4.5f), Vec3f(9, 0, 0), Vec3f(0, 0, 9), kDiffuse));
  d.shapes.push_back(sphereShape(Vec3f(0, 2.6f, 0), 0.7f, kGlass));
  d.shapes.push_back(sphereShape(Vec3f(3, 1.2f, 0), 0.8f, kMirror));
  ShapeDescription smooth =
      quadShape(Vec3f(-4, 1.5f, -1), Vec3f(0, 0, 2), Vec3f(2, 0.2f, 0), kWater);
  smooth.normals = {normalize(Vec3f(-0.3f, 1, -0.2f)), normalize(Vec3f(-0.1f, 1, 0.35f)),
                    normalize(Vec3f(0.25f, 1, 0.3f)), normalize(Vec3f(0.2f, 1, -0.25f))};
  d.shapes.push_back(smooth);
  d.shapes.push_back(quadShape(Vec3f(-1, 1.5f, 2), Vec3f(0, 0, 2), Vec3f(2, 0, 0), kWater));
  return d;
}

PathVertex surfacePoint(const Scene& scene, const Vec3f& from, const Vec3f& to) {
  SurfaceHit h;
  Ray r;
  r.o = from;
  r.d = normalize(to - from);
  EXPECT_TRUE(scene.intersect(r, &h));
  PathVertex v;
  v.p = h.p;
  v.n = h.ng;
  v.ns = h.ns;
  v.shape = h.shape;
  v.primitive = int(h.primitive);
  return v;
}

// The chain traced from `start` in direction w through the given lobes (true: reflection),
// the last vertex wherever it lands; false when it does not land on `endShape`.
bool traceChain(const MutationContext& context, const PathVertex& start, Vec3f w,
                const std::vector<bool>& reflections, int endShape, Path* chain) {
  chain->vertices.assign(1, start);
  for (size_t i = 0; i <= reflections.size(); ++i) {
    PathVertex next;
    if (!traceVertex(context, chain->vertices.back(), w, &next)) return false;
    chain->vertices.push_back(next);
    if (i == reflections.size()) break;
    if (!specularBounce(context.scene, next, chain->vertices[i].p, reflections[i], &w))
      return false;
  }
  return chain->vertices.back().shape == endShape;
}

// A central difference of step h and one of h / 2 combined so that their h^2 errors cancel
// (Richardson): steps large enough that the float rounding of the traced points stays near 1e-4
// of the difference.
template <typename Difference>
Vec3f richardson(double h, Difference difference) {
  return (difference(h / 2) * 4.0f - difference(h)) / 3.0f;
}

// |d omega / dA| at the chain's first vertex by central differences of the traced end point:
// the directions turned by +-delta about two axes normal to w.
double finiteDifferenceSolidAnglePerArea(const MutationContext& context, const PathVertex& start,
                                         const Vec3f& w, const std::vector<bool>& reflections,
                                         int endShape) {
  const Frame frame(w);
  Vec3f d[2];
  for (int axis = 0; axis < 2; ++axis) {
    const Vec3f e = axis == 0 ? frame.s : frame.t;
    d[axis] = richardson(1e-2, [&](double delta) {
      Path plus, minus;
      EXPECT_TRUE(traceChain(context, start, normalize(w + e * float(delta)), reflections, endShape,
                             &plus));
      EXPECT_TRUE(traceChain(context, start, normalize(w - e * float(delta)), reflections, endShape,
                             &minus));
      return (plus.vertices.back().p - minus.vertices.back().p) / float(2 * std::atan(delta));
    });
  }
  return 1 / double(length(cross(d[0], d[1])));
}

// The derivative of the first inner vertex's tangent coordinates with respect to the end's, x_a
// held, as the inverse of the traced map's: aiming from x_a at points of x_{a+1}'s tangent plane
// (+-delta along its basis) and reading where the chain ends in x_b's.
Matrix2 finiteDifferenceDerivative(const MutationContext& context, const Path& chain,
                                   const std::vector<bool>& reflections) {
  const Scene& scene = context.scene;
  const int b = chain.length();
  SurfaceDifferential first, end;
  EXPECT_TRUE(scene.surfaceDifferential(chain[1].shape, chain[1].primitive, chain[1].p, chain[1].n,
                                        &first));
  EXPECT_TRUE(
      scene.surfaceDifferential(chain[b].shape, chain[b].primitive, chain[b].p, chain[b].n, &end));
  Matrix2 forward;
  for (int axis = 0; axis < 2; ++axis) {
    const Vec3f e = axis == 0 ? first.dpdu : first.dpdv;
    const Vec3f d = richardson(1e-2, [&](double delta) {
      Vec3f ends[2];
      for (int side = 0; side < 2; ++side) {
        const Vec3f q = chain[1].p + e * float(side == 0 ? delta : -delta);
        const Vec3f w = normalize(q - scene.spawnRay(chain[0].p, chain[0].n, q - chain[0].p).o);
        Path traced;
        EXPECT_TRUE(traceChain(context, chain[0], w, reflections, chain[b].shape, &traced));
        ends[side] = traced.vertices.back().p;
      }
      return (ends[0] - ends[1]) / float(2 * delta);
    });
    forward.m[0][axis] = dot(d, end.dpdu);
    forward.m[1][axis] = dot(d, end.dpdv);
  }
  const double det = forward.determinant();
  Matrix2 inverse;
  inverse.m[0][0] = forward.m[1][1] / det;
  inverse.m[0][1] = -forward.m[0][1] / det;
  inverse.m[1][0] = -forward.m[1][0] / det;
  inverse.m[1][1] = forward.m[0][0] / det;
  return inverse;
}

struct ChainCase {
  const char* name;
  Vec3f from, towards;  // the start point is where from -> towards first meets a surface
  Vec3f direction;      // the chain's first direction from there
  std::vector<bool> reflections;
  int endShape;
};

std::vector<ChainCase> chainCases() {
  return {
      {"glass ball, two refractions",
       Vec3f(0.25f, 3.9f, 0.1f),
       Vec3f(0.25f, 5, 0.1f),
       normalize(Vec3f(-0.1f, -1, 0.05f)),
       {false, false},
       0},
      // Down onto the ball's left flank, where the normal is 25 degrees above the horizon, so
      // that the reflection goes down to the floor.
      {"mirror ball, one reflection",
       Vec3f(2.275f, 3.9f, 0.03f),
       Vec3f(2.275f, 5, 0.03f),
       normalize(Vec3f(0, -1, 0.01f)),
       {true},
       0},
      {"smooth-shaded water, one refraction",
       Vec3f(-3.3f, 3.9f, 0.2f),
       Vec3f(-3.3f, 5, 0.2f),
       normalize(Vec3f(0.1f, -1, -0.08f)),
       {false},
       0},
      {"flat water, one refraction",
       Vec3f(-0.2f, 3.9f, 2.7f),
       Vec3f(-0.2f, 5, 2.7f),
       normalize(Vec3f(0.3f, -1, -0.2f)),
       {false},
       0},
  };
}

TEST(SpecularManifold, SolidAnglePerAreaMatchesTracedChainsFromEitherEnd) {
  Scene scene(chainScene());
  MutationContext context{scene, -1};
  for (const ChainCase& c : chainCases()) {
    const PathVertex start = surfacePoint(scene, c.from, c.towards);
    Path chain;
    ASSERT_TRUE(traceChain(context, start, c.direction, c.reflections, c.endShape, &chain))
        << c.name;
    const int b = chain.length();
    ASSERT_TRUE(isSpecularChain(scene, chain, 0, b)) << c.name;
    // From the start: d omega_a / dA_b.
    const double analytic = chainSolidAnglePerArea(scene, chain, 0, b, true);
    const double traced =
        finiteDifferenceSolidAnglePerArea(context, start, c.direction, c.reflections, c.endShape);
    EXPECT_NEAR(analytic / traced, 1.0, 2e-3) << c.name << ": from the start";
    // From the end, back through the same lobes in reverse order: d omega_b / dA_a.
    std::vector<bool> back(c.reflections.rbegin(), c.reflections.rend());
    const Vec3f wBack = normalize(chain[b - 1].p - chain[b].p);
    const double analyticBack = chainSolidAnglePerArea(scene, chain, 0, b, false);
    const double tracedBack =
        finiteDifferenceSolidAnglePerArea(context, chain[b], wBack, back, start.shape);
    EXPECT_NEAR(analyticBack / tracedBack, 1.0, 2e-3) << c.name << ": from the end";
    Matrix2 derivative;
    ASSERT_TRUE(specularChainDerivative(scene, chain, 0, b, true, &derivative));
    const Matrix2 traced2 = finiteDifferenceDerivative(context, chain, c.reflections);
    double largest = 0;
    for (const auto& row : derivative.m)
      for (double v : row) largest = std::max(largest, std::fabs(v));
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 2; ++j) {
        EXPECT_NEAR(derivative.m[i][j], traced2.m[i][j], 2e-3 * largest)
            << c.name << ": d u_1 / d u_b [" << i << "][" << j << "]";
      }
    }
    std::printf("%s: d omega/dA %.6g (traced %.6g), back %.6g (traced %.6g)\n", c.name, analytic,
                traced, analyticBack, tracedBack);
  }
}

TEST(SpecularManifold, SolidAnglePerAreaIsReciprocalUpToEtendue) {
  // Where shading normals are the surfaces' own (Fermat's principle holds): the glass and mirror
  // balls and the flat water, whose far end lies in water (eta 1.33).
  Scene scene(chainScene());
  MutationContext context{scene, -1};
  const std::vector<ChainCase> cases = chainCases();
  for (int i : {0, 1, 3}) {
    const ChainCase& c = cases[size_t(i)];
    Path chain;
    ASSERT_TRUE(traceChain(context, surfacePoint(scene, c.from, c.towards), c.direction,
                           c.reflections, c.endShape, &chain));
    const int b = chain.length();
    const double etaB = i == 3 ? 1.33 : 1.0;
    const double cosA = absDot(chain[0].n, normalize(chain[1].p - chain[0].p));
    const double cosB = absDot(chain[b].n, normalize(chain[b - 1].p - chain[b].p));
    const double forward = cosA * chainSolidAnglePerArea(scene, chain, 0, b, true);
    const double backward = etaB * etaB * cosB * chainSolidAnglePerArea(scene, chain, 0, b, false);
    EXPECT_NEAR(forward / backward, 1.0, 1e-4) << c.name;
  }
}

// The measure ratio of a flat mirror in closed form: with x_a and x_b at heights ha and hb over
// it, x_b's mirror image is where the unfolded chain ends, so d u_s / d u_b = ha / (ha + hb) (the
// mirror point moves with it, scaled), and the ratio is cos_b / d_sb^2 over its square.
TEST(SpecularManifold, MeasureRatioOfAFlatMirrorInClosedForm) {
  SceneDescription d = opticsBench();
  d.shapes.push_back(quadShape(Vec3f(-5, 0, -5), Vec3f(0, 0, 10), Vec3f(10, 0, 0), kMirror));
  d.shapes.push_back(quadShape(Vec3f(-5, 3, -5), Vec3f(10, 0, 0), Vec3f(0, 0, 10), kDiffuse));
  d.shapes.push_back(quadShape(Vec3f(1.5f, 1, -5), Vec3f(3, 0, 0), Vec3f(0, 0, 10), kDiffuse));
  Scene scene(d);
  MutationContext context{scene, -1};
  // From the ceiling at (-2, 3, 0) (ha = 3) to the shelf at (2, 1, 0) (hb = 1), by the mirror
  // point (1, 0, 0), 3/4 of the way to the shelf's image (2, -1, 0).
  const PathVertex start = surfacePoint(scene, Vec3f(-2, 2, 0), Vec3f(-2, 5, 0));
  Path chain;
  ASSERT_TRUE(traceChain(context, start, normalize(Vec3f(3, -3, 0)), {true}, 2, &chain));
  // Rays leave each vertex 1e-5 of the scene's size off its surface: the traced chain is the
  // ideal one within a few such offsets, and so is its ratio.
  EXPECT_LT(length(chain[2].p - Vec3f(2, 1, 0)), 3e-5f * (2 + scene.extent()));
  const double ha = 3, hb = 1, dsb = std::sqrt(2.0), cosB = hb / dsb;
  EXPECT_NEAR(logSpecularChainMeasureRatio(scene, chain, 0, 2),
              std::log(cosB / (dsb * dsb) * (ha + hb) * (ha + hb) / (ha * ha)), 3e-4);
}

// --- The walk ------------------------------------------------------------------------------

// Residuals r_0, r_1, ... that fall quadratically once small: every step that starts below 0.1
// (a fiftieth of the scene) ends below 2 r_k^2 (a Newton step's error, with the curvature of
// these chains) or below the walk's tolerance.
void expectQuadratic(const std::vector<double>& residuals, double tolerance, const char* name) {
  int checked = 0;
  for (size_t k = 0; k < residuals.size(); ++k) {
    std::printf("%s: step %zu, distance %.3g\n", name, k, residuals[k]);
    if (k + 1 < residuals.size() && residuals[k] < 0.1) {
      EXPECT_LE(residuals[k + 1], std::max(2.0 * residuals[k] * residuals[k], tolerance))
          << name << ", step " << k;
      ++checked;
    }
  }
  EXPECT_GE(checked, 2) << name << ": too few steps to tell the order";
  EXPECT_LT(residuals.back(), tolerance) << name;
}

TEST(ManifoldWalk, ReachesTheClosedFormSolutionQuadratically) {
  SceneDescription d = opticsBench();
  // A mirror floor, a wall at x = -3 facing +x where the chain starts, a wall at x = 3 facing
  // -x where its end moves; a mirror ball and a glass ball further along z between two walls.
  d.shapes.push_back(quadShape(Vec3f(-5, 0, -5), Vec3f(0, 0, 10), Vec3f(10, 0, 0), kMirror));
  d.shapes.push_back(quadShape(Vec3f(-3, 0, -5), Vec3f(0, 5, 0), Vec3f(0, 0, 10), kDiffuse));
  d.shapes.push_back(quadShape(Vec3f(3, 0, -5), Vec3f(0, 0, 10), Vec3f(0, 5, 0), kDiffuse));
  d.shapes.push_back(sphereShape(Vec3f(0, 2.5f, 12), 1, kMirror));
  d.shapes.push_back(quadShape(Vec3f(-3, 0, 6), Vec3f(0, 5, 0), Vec3f(0, 0, 14), kDiffuse));
  d.shapes.push_back(quadShape(Vec3f(3, 0, 6), Vec3f(0, 0, 14), Vec3f(0, 5, 0), kDiffuse));
  d.shapes.push_back(sphereShape(Vec3f(0, 2.5f, 16), 0.7f, kGlass));
  Scene scene(d);
  MutationContext context{scene, -1};

  struct WalkCase {
    const char* name;
    Vec3f start, firstDirection;  // on the left wall, the initial chain's direction
    std::vector<bool> reflections;
    int endShape;
    Vec3f target;  // on the right wall
    std::vector<Vec3f> solution;
  };
  // Plane mirror: the target's mirror image (3, -2, 1) joined to the start (-3, 3, -1) crosses
  // y = 0 at 3/5 of the way.
  const Vec3f planeStart(-3, 3, -1), planeTarget(3, 2, 1);
  const Vec3f image(planeTarget.x, -planeTarget.y, planeTarget.z);
  const Vec3f planeSolution = planeStart + (image - planeStart) * 0.6f;
  const std::vector<WalkCase> cases = {
      {"plane mirror",
       planeStart,
       normalize(Vec3f(2.5f, -3, -0.4f)),
       {true},
       2,
       planeTarget,
       {planeSolution}},
      // Symmetric about x = 0: the reflection at the ball's top.
      {"mirror ball",
       Vec3f(-3, 4, 12),
       normalize(Vec3f(3.2f, -0.6f, 0.35f)),
       {true},
       5,
       Vec3f(3, 4, 12),
       {Vec3f(0, 3.5f, 12)}},
      // Through the glass ball's centre, undeviated.
      {"glass ball",
       Vec3f(-3, 2.5f, 16),
       normalize(Vec3f(3, 0.25f, -0.2f)),
       {false, false},
       5,
       Vec3f(3, 2.5f, 16),
       {Vec3f(-0.7f, 2.5f, 16), Vec3f(0.7f, 2.5f, 16)}},
  };
  for (const WalkCase& c : cases) {
    const PathVertex start = surfacePoint(scene, c.start + Vec3f(0.5f, 0, 0), c.start);
    Path x;
    ASSERT_TRUE(traceChain(context, start, c.firstDirection, c.reflections, c.endShape, &x))
        << c.name;
    const int b = x.length();
    const PathVertex target = surfacePoint(scene, c.target - Vec3f(0.5f, 0, 0), c.target);
    Path y;
    std::vector<double> residuals;
    ManifoldWalkStats stats;
    const bool walked = manifoldWalk(context, x, 0, b, target, &y, &stats, &residuals);
    ASSERT_TRUE(walked) << c.name;
    EXPECT_EQ(stats.walks, 1u);
    EXPECT_EQ(stats.converged, 1u);
    expectQuadratic(residuals, manifoldWalkTolerance(scene, target.p), c.name);
    // Rays leave each vertex a little off its surface (1e-5 of the coordinates and the scene's
    // size): the chain they trace is the exact one within a few such offsets.
    const float offsets = 3e-5f * (maxAbsComponent(target.p) + scene.extent());
    for (size_t i = 0; i < c.solution.size(); ++i) {
      EXPECT_LT(length(y[int(i) + 1].p - c.solution[i]), offsets)
          << c.name << ", vertex " << i + 1 << " at " << y[int(i) + 1].p.x << " "
          << y[int(i) + 1].p.y << " " << y[int(i) + 1].p.z;
    }
    EXPECT_EQ(y[b].p.x, target.p.x);  // the end is the target itself
  }
}

TEST(ManifoldWalk, CountsTheWalksThatFail) {
  Scene scene(chainScene());
  MutationContext context{scene, -1};
  const ChainCase c = chainCases()[1];  // the mirror ball
  Path x;
  ASSERT_TRUE(traceChain(context, surfacePoint(scene, c.from, c.towards), c.direction,
                         c.reflections, c.endShape, &x));
  // A target on the floor that no reflection in the ball reaches from the start: under the ball.
  const PathVertex target = surfacePoint(scene, Vec3f(3, 0.2f, 0), Vec3f(3, -1, 0));
  ManifoldWalkStats stats;
  Path y;
  EXPECT_FALSE(manifoldWalk(context, x, 0, 2, target, &y, &stats));
  EXPECT_EQ(stats.walks, 1u);
  EXPECT_EQ(stats.converged, 0u);
  EXPECT_GT(stats.halvings, 0u);
  // Lost, and counted once, by its cause: every projection towards it missed the ball or came
  // no closer until the step vanished.
  for (int cause = 0; cause < int(WalkLoss::kCount); ++cause) {
    EXPECT_EQ(stats.lost[cause], cause == int(WalkLoss::kStepVanished) ? 1u : 0u)
        << walkLossName(WalkLoss(cause));
  }
  // A chain that is not specular from x_0 to x_1 (its first inner vertex is the end itself).
  EXPECT_FALSE(manifoldWalk(context, x, 0, 1, target, &y, &stats));
  EXPECT_EQ(stats.walks, 2u);
  EXPECT_EQ(stats.lost[int(WalkLoss::kNotAChain)], 1u);
}

// The same solution, found again by a walk held to its tolerance at the chain's end, lies a few
// tolerances off where the chain's edges are millimetres long; the comparison takes it as the
// same solution then, and a chain a visible distance off as another.
TEST(ManifoldWalk, SameSolutionIsHeldToTheWalksPrecision) {
  Path a;
  a.vertices.resize(4);
  a[0].p = Vec3f(0, 0, 0);
  a[1].p = Vec3f(0.003f, 0, 0);  // edges of 3 mm: a thousandth is 3 um
  a[2].p = Vec3f(0.006f, 0, 0);
  a[3].p = Vec3f(0.009f, 0, 0);
  a[1].shape = a[2].shape = 2;
  const double tolerance = 3e-6;
  Path near = a, far = a, other = a;
  near[1].p.y += 20 * float(tolerance);  // 60 um: 20 tolerances
  far[1].p.y += 200 * float(tolerance);  // 0.6 mm: another solution
  other[2].shape = 3;
  EXPECT_TRUE(sameSpecularChain(a, near, 0, 3, tolerance));
  EXPECT_FALSE(sameSpecularChain(a, near, 0, 3));  // a thousandth of the edge alone
  EXPECT_FALSE(sameSpecularChain(a, far, 0, 3, tolerance));
  EXPECT_FALSE(sameSpecularChain(a, other, 0, 3, tolerance));
  EXPECT_TRUE(sameSpecularChain(a, a, 0, 3, tolerance));
}

// A chain followed across an edge a few millimetres long meets the law of reflection at both
// ends of it, to float precision. Two mirrors meet at 90 degrees in a groove under a diffuse
// ceiling; a ray straight down strikes the first 2.3 mm from the groove's floor and crosses
// 3.3 mm to the second, which sends it straight back up.
// A ray leaving a mirror from spawnRay's origin, 3e-5 off the surface here (1e-5 of the
// scene), arrives turned by that offset over the edge's length: 0.01-0.02 rad, which the
// manifold walk's constraints would count against the chain.
TEST(ManifoldWalk, FollowedChainsMeetTheirConstraintsOnMillimetreEdges) {
  SceneDescription d = opticsBench();
  const float h = std::sqrt(0.5f);
  const Vec3f alongA(-h, h, 0), alongB(h, h, 0);
  d.shapes.push_back(quadShape(Vec3f(0, 0, -1), alongA, Vec3f(0, 0, 2), kMirror));  // faces +x
  d.shapes.push_back(quadShape(Vec3f(0, 0, -1), Vec3f(0, 0, 2), alongB, kMirror));  // faces -x
  d.shapes.push_back(quadShape(Vec3f(-3, 1, -3), Vec3f(6, 0, 0), Vec3f(0, 0, 6), kDiffuse));
  Scene scene(d);
  MutationContext context{scene, -1};
  const Vec3f onA = alongA * 0.0023f;
  const PathVertex start = surfacePoint(scene, Vec3f(onA.x, 0.5f, 0.1f), Vec3f(onA.x, 1.5f, 0.1f));
  ASSERT_EQ(start.shape, 2);
  const Vec3f down(0, -1, 0);
  Path x;
  ASSERT_TRUE(traceChain(context, start, down, {true, true}, 2, &x));
  ASSERT_EQ(x.vertices[1].shape, 0);
  ASSERT_EQ(x.vertices[2].shape, 1);
  Path y = x;
  ASSERT_TRUE(followSpecularChain(context, x, &y, 0, 3, down));
  const double edge = length(y[2].p - y[1].p);
  EXPECT_NEAR(edge, 0.0023 * std::sqrt(2.0), 1e-4);  // 3.3 mm
  for (int i = 1; i <= 2; ++i) {
    const Vec3f wi = normalize(y[i - 1].p - y[i].p), wo = normalize(y[i + 1].p - y[i].p);
    const Vec3f n = y[i].n;
    const Vec3f mirrored = n * (2 * dot(wi, n)) - wi;
    const double error = angleBetween(mirrored, wo);
    std::printf("vertex %d: the law of reflection missed by %.3g rad\n", i, error);
    EXPECT_LT(error, 1e-5) << "vertex " << i;
  }
}

}  // namespace
}  // namespace farm
