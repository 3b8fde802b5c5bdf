// Acceptance ratios of paths whose contribution no float holds: 100 diffuse bounces inside a
// sphere that emits 1e9, with radius 1 (f near 1e-150), 1e4 (1e-950) and 1e-4 (1e700: beyond a
// double too). The contribution stays a finite logarithm, and every mutation's acceptance ratio
// is a number or minus infinity, never NaN or plus infinity.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>

#include "common/mcmc/mlt_chain.h"
#include "common/sampling/warp.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"

namespace farm {
namespace {

// A path of `bounces` surface vertices on the sphere, every edge inside it (so unoccluded), the
// last one in front of the camera at the centre.
Path longPath(const Scene& scene, float radius, int bounces, Rng& rng) {
  Path x;
  for (int i = 0; i <= bounces; ++i) {
    Vec3f d = i == bounces ? normalize(Vec3f(0.05f * (rng.nextFloat() - 0.5f),
                                             0.05f * (rng.nextFloat() - 0.5f), 1))
                           : squareToUniformSphere({rng.nextFloat(), rng.nextFloat()});
    PathVertex v;
    v.kind = i == 0 ? PathVertex::Kind::Light : PathVertex::Kind::Surface;
    v.p = d * radius;
    v.n = v.ns = -d;
    v.shape = 0;
    v.light = scene.lightOf(0);
    x.vertices.push_back(v);
  }
  PathVertex camera;
  camera.kind = PathVertex::Kind::Camera;
  x.vertices.push_back(camera);
  return x;
}

TEST(ExtremePaths, HundredBouncesUnderABillionStayFinite) {
  for (float radius : {1.0f, 1e4f, 1e-4f}) {
    Scene scene(whiteFurnace(0.9f, 200, Spectrum(1e9f, 5e8f, 2.5e8f), 32, radius, Vec3f(0.0f)));
    MutationContext context{scene, 200};
    const BidirectionalMutation bidirectional(context);
    const LensSubpathMutation lensSubpath(context);
    const LensPerturbation lens(context);
    const CausticPerturbation caustic(context);
    const Mutation* mutations[] = {&bidirectional, &lensSubpath, &lens, &caustic};
    Rng rng(3, 3);
    int moved = 0;
    for (int trial = 0; trial < 20; ++trial) {
      Path x = longPath(scene, radius, 100, rng);
      PathContribution fx = x.contribution(scene, 200);
      ASSERT_TRUE(fx.carriesLight()) << "radius " << radius;
      ASSERT_TRUE(std::isfinite(fx.logLuminance));
      EXPECT_GT(std::fabs(fx.logLuminance), std::log(FLT_MAX)) << "radius " << radius;
      for (const Mutation* m : mutations) {
        if (!m->appliesTo(x)) continue;
        for (int k = 0; k < 5; ++k) {
          Path y;
          MutationRecord record;
          if (!m->propose(x, rng, &y, &record)) continue;
          PathContribution fy = y.contribution(scene, 200);
          if (!fy.carriesLight()) continue;
          const double logR = logAcceptanceRatio(*m, x, fx, y, fy, record, 1, 1);
          EXPECT_FALSE(std::isnan(logR)) << mutationName(m->type()) << " radius " << radius;
          EXPECT_FALSE(logR == INFINITY) << mutationName(m->type()) << " radius " << radius;
          moved += std::isfinite(logR);
        }
      }
    }
    EXPECT_GT(moved, 50) << "radius " << radius << ": too few proposals to tell";
  }
}

}  // namespace
}  // namespace farm
