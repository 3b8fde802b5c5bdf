#include "common/scene/camera.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/sampling/rng.h"

namespace farm {
namespace {

CameraDescription lensCamera() {
  CameraDescription d;
  d.toWorld = Matrix4::lookAt({1, 2, 3}, {1, 2, 10}, {0, 1, 0});
  d.fovDegrees = 40;
  d.width = 80;
  d.height = 60;
  d.lensRadius = 0.25f;
  d.focusDistance = 5;
  return d;
}

TEST(Camera, LensPointsCoverTheDiskUniformly) {
  Camera cam(lensCamera());
  ASSERT_TRUE(cam.hasLens());
  Rng rng(3, 1);
  double sumR2 = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    Vec3f p = cam.lensPoint({rng.nextFloat(), rng.nextFloat()});
    Vec3f off = p - cam.position();
    EXPECT_NEAR(dot(off, cam.forward()), 0, 1e-6);  // on the lens plane
    const double r2 = lengthSquared(off);
    EXPECT_LE(r2, 0.25 * 0.25 * (1 + 1e-5));
    sumR2 += r2;
  }
  // Uniform on a disk of radius R: E[r^2] = R^2 / 2, standard deviation R^2 / sqrt(12).
  EXPECT_NEAR(sumR2 / n, 0.25 * 0.25 / 2, 4 * 0.0625 / std::sqrt(12.0 * n));
  CameraDescription pinhole = lensCamera();
  pinhole.lensRadius = 0;
  Camera p(pinhole);
  EXPECT_FALSE(p.hasLens());
  EXPECT_EQ(p.lensPoint({0.3f, 0.9f}).x, p.position().x);
}

TEST(Camera, LensRaysMeetOnTheFocusPlaneAndProjectBack) {
  Camera cam(lensCamera());
  Rng rng(5, 1);
  for (int i = 0; i < 200; ++i) {
    const Vec2f film(rng.nextFloat() * 80, rng.nextFloat() * 60);
    const Ray center = cam.generateRay(film);  // through the lens's centre
    const Vec3f focus = center.o + center.d * (5 / dot(center.d, cam.forward()));
    for (int k = 0; k < 4; ++k) {
      const Vec3f lens = cam.lensPoint({rng.nextFloat(), rng.nextFloat()});
      const Ray r = cam.generateRay(film, lens);
      EXPECT_NEAR(r.o.x, lens.x, 1e-6);
      const Vec3f hit = r.o + r.d * (5 / dot(r.d, cam.forward()));
      EXPECT_NEAR(length(hit - focus), 0, 1e-4);
      Vec2f back;
      ASSERT_TRUE(cam.project(lens, r.d, &back));
      EXPECT_NEAR(back.x, film.x, 2e-3);
      EXPECT_NEAR(back.y, film.y, 2e-3);
      // The direction density does not depend on the lens point (see camera.h).
      const float c = dot(r.d, cam.forward());
      EXPECT_NEAR(cam.importance(lens, r.d) * c * c * c,
                  cam.importance(center.o, center.d) * std::pow(dot(center.d, cam.forward()), 3),
                  1e-4);
    }
  }
}

}  // namespace
}  // namespace farm
