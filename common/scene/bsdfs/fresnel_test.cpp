// The Fresnel equations against their closed-form limits, and the two forms of the dielectric's
// (from one cosine, and from both) against each other.
#include "common/scene/bsdfs/fresnel.h"

#include <gtest/gtest.h>

#include <cmath>

namespace farm {
namespace {

TEST(Fresnel, Limits) {
  float cosT;
  EXPECT_NEAR(fresnelDielectric(1.0f, 1.5f, &cosT), 0.04f, 1e-6f);  // ((1.5-1)/(1.5+1))^2
  EXPECT_EQ(fresnelDielectric(-0.1f, 1.5f, &cosT), 1.0f);           // total internal reflection
  Spectrum f = fresnelConductor(1.0f, Spectrum(0.2f), Spectrum(3.9f));
  // normal incidence: ((n-1)^2 + k^2) / ((n+1)^2 + k^2)
  EXPECT_NEAR(f.x, (0.64f + 15.21f) / (1.44f + 15.21f), 1e-5f);
}

// fresnelOfRefraction, from both cosines, is fresnelDielectric's value from one, the same from
// either side (a refraction and its reverse reflect alike), and Snell's law holds for
// refracted()'s direction.
TEST(Fresnel, BothFormsAgreeAndAreReciprocal) {
  for (float eta : {1.0001f, 1.33f, 2.4f, 4.0f})
    for (float cosI : {0.05f, 0.3f, 0.7f, 1.0f}) {
      float cosT;
      const float f = fresnelDielectric(cosI, eta, &cosT);
      ASSERT_LT(f, 1.0f);
      EXPECT_NEAR(fresnelOfRefraction(cosI, 1.0f, cosT, eta), f, 2e-6f) << eta << " " << cosI;
      EXPECT_EQ(fresnelOfRefraction(cosI, 1.0f, cosT, eta),
                fresnelOfRefraction(cosT, eta, cosI, 1.0f));
      const float sinI = std::sqrt(1 - cosI * cosI);
      const Vec3f wo(sinI, 0, cosI);
      const Vec3f wt = refracted(wo, eta, cosT);
      EXPECT_NEAR(wt.z, -cosT, 1e-6f);
      EXPECT_NEAR(-wt.x * eta, sinI, 2e-6f * eta);  // tangential part reversed, scaled by 1/eta
      // Refracting the transmitted direction back returns wo.
      float cosBack;
      fresnelDielectric(wt.z, eta, &cosBack);
      const Vec3f back = refracted(-wt, 1 / eta, cosBack);
      EXPECT_NEAR(back.x, -wo.x, 1e-5f);
      EXPECT_NEAR(back.z, -wo.z, 1e-5f);
    }
}

}  // namespace
}  // namespace farm
