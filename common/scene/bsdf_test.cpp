// BSDF sampling must agree with evaluation and density: the weight returned by sample() is
// f cos / pdf, pdf() reproduces the sampled density, and the albedo estimated by importance
// sampling equals the one estimated by uniform hemisphere sampling of eval() (both unbiased
// estimators of the same integral; tolerances from their standard errors).
#include "common/scene/bsdf.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/sampling/rng.h"
#include "common/sampling/warp.h"

namespace farm {
namespace {

BsdfDescription conductor(MicrofacetDistribution d, float alpha) {
  BsdfDescription b;
  b.type = BsdfDescription::Type::RoughConductor;
  b.distribution = d;
  b.alpha = alpha;
  b.eta = Spectrum(0.200438f, 0.924033f, 1.10221f);
  b.k = Spectrum(3.91295f, 2.45285f, 2.14219f);
  b.twoSided = true;
  return b;
}

struct Estimate {
  double mean = 0, stdError = 0;
};

template <typename F>
Estimate monteCarlo(int n, F&& f) {
  double s = 0, s2 = 0;
  for (int i = 0; i < n; ++i) {
    double v = f(i);
    s += v;
    s2 += v * v;
  }
  Estimate e;
  e.mean = s / n;
  e.stdError = std::sqrt(std::max(0.0, s2 / n - e.mean * e.mean) / n);
  return e;
}

// The albedo of a microfacet conductor at wo by quadrature over the microfacet normal m, with
// eval() alone: wi is the reflection of wo about m and d(omega_i) = 4 |wo.m| d(omega_m), so the
// albedo is the integral of f(wo, wi) |cos wi| 4 |wo.m| over m. m is parameterized by
// x = tan(theta_m) / alpha mapped from [0, 1), so that lobes of any width are resolved.
double quadratureAlbedo(const Bsdf& bsdf, float alpha, const Vec3f& wo, int nTheta, int nPhi) {
  double sum = 0;
  for (int i = 0; i < nTheta; ++i) {
    const double u = (i + 0.5) / nTheta;
    const double x = u / (1 - u);
    const double theta = std::atan(alpha * x);
    const double dTheta = alpha / (1 + alpha * alpha * x * x) / ((1 - u) * (1 - u)) / nTheta;
    for (int j = 0; j < nPhi; ++j) {
      const double phi = 2 * M_PI * (j + 0.5) / nPhi;
      const Vec3f m(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                    float(std::cos(theta)));
      const float womDot = dot(wo, m);
      if (womDot <= 0) continue;
      const Vec3f wi = 2 * womDot * m - wo;
      if (wi.z <= 0) continue;
      sum += double(bsdf.eval(wo, wi, TransportMode::Radiance).y) * wi.z * 4 * womDot *
             std::sin(theta) * dTheta * (2 * M_PI / nPhi);
    }
  }
  return sum;
}

// sample() against eval() and pdf(), sample by sample, and its albedo (the mean weight) against
// an estimate that does not use it: a numerical quadrature of eval() for microfacet lobes, an
// estimate by uniform sphere sampling of eval() otherwise. The tolerance is the standard error
// of the sampled mean (and of the uniform estimate, where there is one) from the sample count.
void checkSamplingConsistency(const BsdfDescription& desc, float cosThetaO) {
  Bsdf bsdf(desc);
  Vec3f wo(std::sqrt(1 - cosThetaO * cosThetaO), 0, cosThetaO);
  Rng rng(7, 1);
  const int n = 200000;
  Estimate sampled = monteCarlo(n, [&](int) {
    float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
    BsdfSample s;
    if (!bsdf.sample(wo, u, TransportMode::Radiance, &s)) return 0.0;
    Spectrum f = bsdf.eval(wo, s.wi, TransportMode::Radiance);
    float pdf = bsdf.pdf(wo, s.wi);
    // weight == f cos / pdf and pdf() == the sampled density, per sample
    EXPECT_NEAR(pdf, s.pdf, 1e-3f * s.pdf + 1e-5f);
    EXPECT_NEAR(s.weight.y, f.y * std::fabs(s.wi.z) / s.pdf, 1e-3f * s.weight.y + 1e-5f);
    return double(s.weight.y);
  });
  Estimate reference;
  if (desc.type == BsdfDescription::Type::RoughConductor) {
    Vec3f w = wo.z < 0 ? Vec3f(wo.x, wo.y, -wo.z) : wo;  // twosided: the back is the front
    reference.mean = quadratureAlbedo(bsdf, desc.alpha, w, 2000, 256);
    // The quadrature at half the resolution tells its own error.
    reference.stdError =
        std::fabs(reference.mean - quadratureAlbedo(bsdf, desc.alpha, w, 1000, 128));
  } else {
    reference = monteCarlo(n, [&](int) {
      Vec3f wi = squareToUniformSphere({rng.nextFloat(), rng.nextFloat()});
      return double(bsdf.eval(wo, wi, TransportMode::Radiance).y * std::fabs(wi.z)) * 4 * kPi;
    });
  }
  const double tolerance = 4.4 * std::sqrt(sampled.stdError * sampled.stdError +
                                           reference.stdError * reference.stdError);
  EXPECT_NEAR(sampled.mean, reference.mean, tolerance)
      << "cos(theta_o) " << cosThetaO << ", standard error " << sampled.stdError;
  EXPECT_LT(tolerance, 0.02 * reference.mean) << "too loose to tell";
  EXPECT_LE(sampled.mean, 1.0 + tolerance);  // energy conservation
}

TEST(Bsdf, DiffuseSamplingMatchesEvaluation) {
  BsdfDescription d;
  d.reflectance = Spectrum(0.7f);
  d.twoSided = true;
  checkSamplingConsistency(d, 0.8f);
  checkSamplingConsistency(d, -0.3f);
  // The Lambertian albedo is the reflectance: eval() integrated over the hemisphere by uniform
  // sampling (not sample(), whose weight is the reflectance by construction).
  Bsdf bsdf(d);
  Rng rng(1, 2);
  Estimate e = monteCarlo(200000, [&](int) {
    Vec3f wi = squareToUniformSphere({rng.nextFloat(), rng.nextFloat()});
    return double(bsdf.eval(Vec3f(0, 0, 1), wi, TransportMode::Radiance).y * std::fabs(wi.z)) * 4 *
           kPi;
  });
  EXPECT_NEAR(e.mean, 0.7, 4.4 * e.stdError);
  EXPECT_LT(e.stdError, 0.005);
}

TEST(Bsdf, BeckmannSamplingMatchesEvaluation) {
  for (float alpha : {0.05f, 0.25f, 1.0f}) {
    checkSamplingConsistency(conductor(MicrofacetDistribution::Beckmann, alpha), 0.9f);
    checkSamplingConsistency(conductor(MicrofacetDistribution::Beckmann, alpha), 0.2f);
  }
}

TEST(Bsdf, GgxSamplingMatchesEvaluation) {
  for (float alpha : {0.05f, 0.25f, 1.0f}) {
    checkSamplingConsistency(conductor(MicrofacetDistribution::GGX, alpha), 0.9f);
    checkSamplingConsistency(conductor(MicrofacetDistribution::GGX, alpha), 0.2f);
  }
}

TEST(Bsdf, DielectricConservesEnergyAndObeysSnell) {
  BsdfDescription d;
  d.type = BsdfDescription::Type::Dielectric;
  d.intIOR = 1.5f;
  d.extIOR = 1.0f;
  Bsdf bsdf(d);
  Vec3f wo = normalize(Vec3f(0.6f, 0, 0.8f));
  Rng rng(3, 3);
  int reflected = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
    BsdfSample s;
    ASSERT_TRUE(bsdf.sample(wo, u, TransportMode::Importance, &s));
    EXPECT_TRUE(s.delta);
    EXPECT_NEAR(s.weight.x, 1.0f, 1e-6f);  // importance is not scaled by eta^2
    if (s.wi.z > 0) {
      ++reflected;
    } else {
      // Snell: sin(theta_t) = sin(theta_i) / 1.5
      float sinT = std::sqrt(1 - s.wi.z * s.wi.z);
      EXPECT_NEAR(sinT, 0.6f / 1.5f, 1e-5f);
    }
  }
  float cosT;
  float F = fresnelDielectric(0.8f, 1.5f, &cosT);
  double p = double(reflected) / n;
  EXPECT_NEAR(p, F, 5 * std::sqrt(F * (1 - F) / n));
  // Radiance entering the denser medium is scaled by 1 / eta^2.
  float u[3] = {0.999f, 0.5f, 0.5f};
  BsdfSample s;
  ASSERT_TRUE(bsdf.sample(wo, u, TransportMode::Radiance, &s));
  EXPECT_NEAR(s.weight.x, 1 / 2.25f, 1e-6f);
}

TEST(Bsdf, FresnelLimits) {
  float cosT;
  EXPECT_NEAR(fresnelDielectric(1.0f, 1.5f, &cosT), 0.04f, 1e-6f);  // ((1.5-1)/(1.5+1))^2
  EXPECT_EQ(fresnelDielectric(-0.1f, 1.5f, &cosT), 1.0f);           // total internal reflection
  Spectrum f = fresnelConductor(1.0f, Spectrum(0.2f), Spectrum(3.9f));
  // normal incidence: ((n-1)^2 + k^2) / ((n+1)^2 + k^2)
  EXPECT_NEAR(f.x, (0.64f + 15.21f) / (1.44f + 15.21f), 1e-5f);
}

}  // namespace
}  // namespace farm

namespace farm {
namespace {

// Stiff cases of DESIGN.md: roughness from 1e-4 to 1, indices of refraction near one and very
// high, grazing angles. Every sample must be finite and non-negative, agree with eval/pdf, and
// the albedo estimated by importance sampling must not exceed one.
TEST(Bsdf, StiffParametersStayFiniteAndConsistent) {
  Rng rng(11, 4);
  for (MicrofacetDistribution d : {MicrofacetDistribution::Beckmann, MicrofacetDistribution::GGX}) {
    for (float alpha : {1e-4f, 1e-3f, 1.0f}) {
      BsdfDescription desc = conductor(d, alpha);
      Bsdf bsdf(desc);
      for (float cosO : {1.0f, 0.5f, 1e-3f}) {
        Vec3f wo(std::sqrt(std::max(0.0f, 1 - cosO * cosO)), 0, cosO);
        double sum = 0;
        const int n = 20000;
        for (int i = 0; i < n; ++i) {
          float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
          BsdfSample s;
          if (!bsdf.sample(wo, u, TransportMode::Radiance, &s)) continue;
          ASSERT_TRUE(isValidRadiance(s.weight)) << alpha << " " << cosO;
          ASSERT_TRUE(std::isfinite(s.pdf) && s.pdf > 0);
          Spectrum f = bsdf.eval(wo, s.wi, TransportMode::Radiance);
          ASSERT_TRUE(isValidRadiance(f));
          // Recomputing the half vector from float directions at a grazing wo is only good to
          // about 1e-7 / cos(theta_o) radians, too coarse for such narrow lobes to recover the
          // density; there the sample's own weight (closed form in m) is what counts.
          if (cosO >= 0.5f) {
            EXPECT_NEAR(bsdf.pdf(wo, s.wi) / s.pdf, 1.0f, 2e-3f) << alpha << " " << cosO;
            EXPECT_NEAR(f.y * std::fabs(s.wi.z) / s.pdf / s.weight.y, 1.0f, 2e-3f);
          }
          sum += s.weight.y;
        }
        EXPECT_LE(sum / n, 1.0 + 1e-3) << "alpha " << alpha << " cos " << cosO;
      }
    }
  }
  for (float ior : {1.0001f, 1.8f, 10.0f}) {
    BsdfDescription desc;
    desc.type = BsdfDescription::Type::Dielectric;
    desc.intIOR = ior;
    desc.extIOR = 1.0f;
    Bsdf bsdf(desc);
    for (float cosO : {1.0f, 1e-4f, -1e-4f, -0.9f}) {
      Vec3f wo(std::sqrt(std::max(0.0f, 1 - cosO * cosO)), 0, cosO);
      for (float u0 : {0.0f, 0.5f, 0.99999f}) {
        float u[3] = {u0, 0.5f, 0.5f};
        BsdfSample s;
        ASSERT_TRUE(bsdf.sample(wo, u, TransportMode::Radiance, &s));
        ASSERT_TRUE(isValidRadiance(s.weight)) << ior << " " << cosO;
        ASSERT_TRUE(isFinite(s.wi));
        EXPECT_NEAR(length(s.wi), 1.0f, 1e-4f);
        EXPECT_GT(s.pdf, 0);
      }
    }
  }
}

}  // namespace
}  // namespace farm

namespace farm {
namespace {

// The Dirac lobes as the path-space mutations see them: every direction sample() produces is
// recognized by specularLobe() as the same lobe, with sample()'s probability and with value /
// probability equal to sample()'s weight, and specularDirection() reproduces it.
TEST(DielectricLobes, SpecularLobeAgreesWithSample) {
  BsdfDescription glass;
  glass.type = BsdfDescription::Type::Dielectric;
  glass.intIOR = 1.5f;
  glass.extIOR = 1.0f;
  Bsdf bsdf(glass);
  Rng rng(3, 3);
  int reflections = 0, refractions = 0;
  for (int i = 0; i < 20000; ++i) {
    Vec3f wo = squareToUniformSphere({rng.nextFloat(), rng.nextFloat()});
    if (std::fabs(wo.z) < 1e-3f) continue;
    for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
      float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
      BsdfSample s;
      ASSERT_TRUE(bsdf.sample(wo, u, mode, &s));
      bool reflection;
      float probability;
      Spectrum value;
      ASSERT_TRUE(bsdf.specularLobe(wo, s.wi, mode, &reflection, &probability, &value))
          << "wo " << wo.x << " " << wo.y << " " << wo.z;
      EXPECT_EQ(reflection, wo.z * s.wi.z > 0);
      EXPECT_FLOAT_EQ(probability, s.pdf);
      EXPECT_NEAR(value.y / probability, s.weight.y, 1e-5f * s.weight.y);
      Vec3f again;
      ASSERT_TRUE(bsdf.specularDirection(wo, reflection, &again));
      EXPECT_GT(dot(again, s.wi), 1 - 1e-6f);  // the same computation: to rounding
      (reflection ? reflections : refractions)++;
    }
  }
  EXPECT_GT(reflections, 1000);
  EXPECT_GT(refractions, 1000);
  // Not a Dirac BSDF: nothing is a Dirac direction.
  Bsdf diffuse{BsdfDescription()};
  Vec3f wi;
  bool reflection;
  float probability;
  Spectrum value;
  EXPECT_FALSE(diffuse.specularDirection(Vec3f(0, 0, 1), true, &wi));
  EXPECT_FALSE(diffuse.specularLobe(Vec3f(0, 0, 1), Vec3f(0, 0, 1), TransportMode::Radiance,
                                    &reflection, &probability, &value));
}

}  // namespace
}  // namespace farm
