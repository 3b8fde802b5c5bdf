// BSDF sampling must agree with evaluation and density: the weight returned by sample() is
// f cos / pdf, pdf() reproduces the sampled density, and the albedo estimated by importance
// sampling equals the one estimated by uniform hemisphere sampling of eval() (both unbiased
// estimators of the same integral; tolerances from their standard errors).
#include "common/scene/bsdf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "common/sampling/rng.h"
#include "common/sampling/warp.h"
#include "common/scene/bsdfs/coating_transmittance.h"
#include "common/scene/bsdfs/fresnel.h"

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

// The albedo at wo of a microfacet BSDF by quadrature over the microfacet normal m, with eval()
// alone, split into its reflected and transmitted parts. m faces wo (facets facing away are
// shadowed); wi is wo's mirror image in m, with d(omega_i) = 4 |wo.m| d(omega_m), or (rough
// dielectrics) wo refracted through m by Snell's law, with d(omega_t) = (eta_i wo.m +
// eta_t wt.m)^2 / (eta_t^2 |wt.m|) d(omega_m) (Walter et al. 2007, eqs. 14 and 17). m is
// parameterized by x = tan(theta_m) / alpha mapped from [0, 1), so that lobes of any width are
// resolved.
struct Albedo {
  double reflected = 0, transmitted = 0;
  double total() const { return reflected + transmitted; }
};

Albedo quadratureAlbedo(const BsdfDescription& desc, const Vec3f& wo, TransportMode mode,
                        int nTheta, int nPhi) {
  const Bsdf bsdf(desc);
  const double alpha = desc.alpha;
  const bool transmits = desc.type == BsdfDescription::Type::RoughDielectric;
  const double etaI = wo.z > 0 ? desc.extIOR : desc.intIOR;
  const double etaT = wo.z > 0 ? desc.intIOR : desc.extIOR;
  Albedo sum;
  for (int i = 0; i < nTheta; ++i) {
    const double u = (i + 0.5) / nTheta;
    const double x = u / (1 - u);
    const double theta = std::atan(alpha * x);
    const double dTheta = alpha / (1 + alpha * alpha * x * x) / ((1 - u) * (1 - u)) / nTheta;
    for (int j = 0; j < nPhi; ++j) {
      const double phi = 2 * M_PI * (j + 0.5) / nPhi;
      const double dOmega = std::sin(theta) * dTheta * (2 * M_PI / nPhi);
      // The facet, turned to wo's side (its distribution is symmetric under the turn).
      const double side = wo.z > 0 ? 1 : -1;
      const double m[3] = {side * std::sin(theta) * std::cos(phi),
                           side * std::sin(theta) * std::sin(phi), side * std::cos(theta)};
      const double w[3] = {wo.x, wo.y, wo.z};
      const double c = w[0] * m[0] + w[1] * m[1] + w[2] * m[2];
      if (c <= 0) continue;
      const Vec3f wr(float(2 * c * m[0] - w[0]), float(2 * c * m[1] - w[1]),
                     float(2 * c * m[2] - w[2]));
      if (wr.z * wo.z > 0)
        sum.reflected += double(bsdf.eval(wo, wr, mode).y) * std::fabs(wr.z) * 4 * c * dOmega;
      if (!transmits) continue;
      const double r = etaI / etaT, k = 1 - r * r * (1 - c * c);
      if (k <= 0) continue;  // total internal reflection at this facet
      const double t[3] = {-r * w[0] + (r * c - std::sqrt(k)) * m[0],
                           -r * w[1] + (r * c - std::sqrt(k)) * m[1],
                           -r * w[2] + (r * c - std::sqrt(k)) * m[2]};
      if (t[2] * wo.z >= 0) continue;
      const double tm = t[0] * m[0] + t[1] * m[1] + t[2] * m[2];  // -sqrt(k)
      const double jacobian =
          (etaI * c + etaT * tm) * (etaI * c + etaT * tm) / (etaT * etaT * std::fabs(tm));
      const Vec3f wt{float(t[0]), float(t[1]), float(t[2])};
      sum.transmitted += double(bsdf.eval(wo, wt, mode).y) * std::fabs(t[2]) * jacobian * dOmega;
    }
  }
  return sum;
}

// A refraction through a rough dielectric whose direction leaves the facet it refracted
// through at under 0.05 of a cosine.
bool refractsNearGrazing(const BsdfDescription& desc, const Vec3f& wo, const Vec3f& wi) {
  if (desc.type != BsdfDescription::Type::RoughDielectric || wo.z * wi.z >= 0) return false;
  const float etaO = wo.z > 0 ? desc.extIOR : desc.intIOR;
  const float etaI = wi.z > 0 ? desc.extIOR : desc.intIOR;
  const Vec3f h = normalize(etaO * wo + etaI * wi);
  return std::fabs(dot(wi, h)) < 0.05f;
}

// sample() against eval() and pdf(), sample by sample, and its albedo (the mean weight) against
// an estimate that does not use it: a numerical quadrature of eval() for microfacet lobes, an
// estimate by uniform sphere sampling of eval() otherwise. The tolerance is the standard error
// of the sampled mean (and of the uniform estimate, where there is one) from the sample count.
void checkSamplingConsistency(const BsdfDescription& desc, float cosThetaO,
                              TransportMode mode = TransportMode::Radiance) {
  Bsdf bsdf(desc);
  Vec3f wo(std::sqrt(1 - cosThetaO * cosThetaO), 0, cosThetaO);
  Rng rng(7, 1);
  // A rough Beckmann dielectric's weights (G1 G1 |wo.m| / (|cos theta_o| cos theta_m), times
  // eta^2 from inside) have a heavy tail at alpha 1 (visible GGX normals' are at most eta^2).
  const int n = desc.type == BsdfDescription::Type::RoughDielectric &&
                        desc.distribution == MicrofacetDistribution::Beckmann
                    ? 1000000
                    : 200000;
  Estimate sampled = monteCarlo(n, [&](int) {
    float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
    BsdfSample s;
    if (!bsdf.sample(wo, u, mode, &s)) return 0.0;
    Spectrum f = bsdf.eval(wo, s.wi, mode);
    float pdf = bsdf.pdf(wo, s.wi);
    // weight == f cos / pdf and pdf() == the sampled density, per sample; except where a
    // refraction leaves its facet within a few degrees of grazing (the critical angle): there
    // the refracted cosine, and with it the facet recomputed from the float directions, is
    // ill-conditioned, and the sample's own weight (closed form in m) is what counts.
    if (refractsNearGrazing(desc, wo, s.wi)) return double(s.weight.y);
    EXPECT_NEAR(pdf, s.pdf, 1e-3f * s.pdf + 1e-5f);
    EXPECT_NEAR(s.weight.y, f.y * std::fabs(s.wi.z) / s.pdf, 1e-3f * s.weight.y + 1e-5f);
    return double(s.weight.y);
  });
  Estimate reference;
  if (desc.type == BsdfDescription::Type::RoughConductor ||
      desc.type == BsdfDescription::Type::RoughDielectric ||
      desc.type == BsdfDescription::Type::Plastic ||
      desc.type == BsdfDescription::Type::CoatedDiffuse) {
    Vec3f w = desc.twoSided && wo.z < 0 ? Vec3f(wo.x, wo.y, -wo.z) : wo;  // the back is the front
    reference.mean = quadratureAlbedo(desc, w, mode, 2000, 256).total();
    // The quadrature at half the resolution tells its own error.
    reference.stdError =
        std::fabs(reference.mean - quadratureAlbedo(desc, w, mode, 1000, 128).total());
  } else {
    reference = monteCarlo(n, [&](int) {
      Vec3f wi = squareToUniformSphere({rng.nextFloat(), rng.nextFloat()});
      return double(bsdf.eval(wo, wi, mode).y * std::fabs(wi.z)) * 4 * kPi;
    });
  }
  const double tolerance = 4.4 * std::sqrt(sampled.stdError * sampled.stdError +
                                           reference.stdError * reference.stdError);
  EXPECT_NEAR(sampled.mean, reference.mean, tolerance)
      << "cos(theta_o) " << cosThetaO << ", standard error " << sampled.stdError;
  EXPECT_LT(tolerance, 0.02 * reference.mean) << "too loose to tell";
  // Energy conservation: the adjoint's albedo at wo is the share of the power arriving from wo
  // that leaves (the radiance form's is not bounded: refraction concentrates radiance).
  if (mode == TransportMode::Importance || desc.type != BsdfDescription::Type::RoughDielectric) {
    EXPECT_LE(sampled.mean, 1.0 + tolerance);
  }
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

BsdfDescription plastic(float alpha, const Spectrum& kd, const Spectrum& ks) {
  BsdfDescription d;
  d.type = BsdfDescription::Type::Plastic;
  d.distribution = MicrofacetDistribution::GGX;
  d.alpha = alpha;
  d.reflectance = kd;
  d.specularReflectance = ks;
  d.intIOR = 1.5f;
  d.extIOR = 1.0f;
  d.twoSided = true;
  return d;
}

TEST(Bsdf, PlasticSamplingMatchesEvaluation) {
  for (float alpha : {0.02f, 0.3f, 1.0f}) {
    for (float c : {0.9f, 0.25f, -0.6f}) {
      checkSamplingConsistency(plastic(alpha, Spectrum(0.5f, 0.3f, 0.2f), Spectrum(0.4f)), c);
      checkSamplingConsistency(plastic(alpha, Spectrum(0.2f), Spectrum(0.9f)), c);
    }
  }
}

// The two lobes, each alone, are the Lambertian and a GGX reflection with a dielectric's Fresnel
// term: at normal incidence on a smooth-ish lobe the glossy albedo is about F(0) = 0.04 for
// index 1.5 (times Ks), and the sum is both (the mixture adds, nothing couples them).
TEST(Bsdf, PlasticIsTheSumOfItsLobes) {
  const Vec3f wo(0, 0, 1);
  const Albedo diffuse = quadratureAlbedo(plastic(0.05f, Spectrum(0.6f), Spectrum(0.0f)), wo,
                                          TransportMode::Radiance, 2000, 256);
  const Albedo glossy = quadratureAlbedo(plastic(0.05f, Spectrum(0.0f), Spectrum(1.0f)), wo,
                                         TransportMode::Radiance, 2000, 256);
  const Albedo both = quadratureAlbedo(plastic(0.05f, Spectrum(0.6f), Spectrum(1.0f)), wo,
                                       TransportMode::Radiance, 2000, 256);
  EXPECT_NEAR(diffuse.total(), 0.6, 0.003);
  EXPECT_NEAR(glossy.total(), 0.04, 0.003);  // ((1.5 - 1) / (1.5 + 1))^2
  EXPECT_NEAR(both.total(), diffuse.total() + glossy.total(), 1e-4);
  // Near grazing (78 degrees) the Fresnel term seen from the air is about 0.3 (less the
  // shadowing); pbrt-v3's, computed from inside the coating, would reflect totally.
  const float c = 0.2f;
  const Albedo grazing =
      quadratureAlbedo(plastic(0.05f, Spectrum(0.0f), Spectrum(1.0f)),
                       Vec3f(std::sqrt(1 - c * c), 0, c), TransportMode::Radiance, 2000, 256);
  EXPECT_GT(grazing.total(), 0.15);
  EXPECT_LT(grazing.total(), 0.4);
  EXPECT_TRUE(Bsdf(plastic(0.05f, Spectrum(0.0f), Spectrum(0.0f))).isBlack());
  EXPECT_FALSE(Bsdf(plastic(0.05f, Spectrum(0.6f), Spectrum(0.0f))).isDelta());
}

BsdfDescription roughGlass(MicrofacetDistribution d, float alpha, float ior = 1.5f) {
  BsdfDescription b;
  b.type = BsdfDescription::Type::RoughDielectric;
  b.distribution = d;
  b.alpha = alpha;
  b.intIOR = ior;
  b.extIOR = 1.0f;
  return b;
}

// ---- The coated diffuse (Mitsuba's roughplastic) ----

BsdfDescription coated(MicrofacetDistribution dist, float alpha, const Spectrum& rho,
                       const Spectrum& ks, float eta = 1.5f, bool nonlinear = false) {
  BsdfDescription d;
  d.type = BsdfDescription::Type::CoatedDiffuse;
  d.distribution = dist;
  d.alpha = alpha;
  d.reflectance = rho;
  d.specularReflectance = ks;
  d.intIOR = eta;
  d.extIOR = 1.0f;
  d.nonlinear = nonlinear;
  d.twoSided = true;
  d.coating = std::make_shared<CoatingTransmittance>(dist, alpha, eta);
  return d;
}

// The coat's table against the rough dielectric's own transmitted albedo, computed from eval()
// by quadratureAlbedo (a different integration of a different function of the same model): from
// outside at several cosines, and from inside through Fdr = 1 - 2 \int T_in(mu) mu dmu. The
// tolerance is the quadrature's own error (two resolutions) plus the table's interpolation.
TEST(CoatingTransmittance, IsTheRoughDielectricsTransmittedAlbedo) {
  for (MicrofacetDistribution dist :
       {MicrofacetDistribution::GGX, MicrofacetDistribution::Beckmann})
    for (float alpha : {0.05f, 0.3f, 0.8f}) {
      const CoatingTransmittance coat(dist, alpha, 1.5f);
      const BsdfDescription glass = roughGlass(dist, alpha, 1.5f);
      for (float mu : {0.15f, 0.5f, 0.95f}) {
        const Vec3f wo(std::sqrt(1 - mu * mu), 0, mu);
        const double fine =
            quadratureAlbedo(glass, wo, TransportMode::Importance, 2000, 256).transmitted;
        const double coarse =
            quadratureAlbedo(glass, wo, TransportMode::Importance, 1000, 128).transmitted;
        EXPECT_NEAR(coat.fromOutside(mu), fine, std::fabs(fine - coarse) + 2e-3)
            << "alpha " << alpha << " mu " << mu;
      }
      // From inside, by the midpoint rule over mu.
      const int n = 40;
      double inside = 0;
      for (int k = 0; k < n; ++k) {
        const double mu = (k + 0.5) / n;
        const Vec3f wo(float(std::sqrt(1 - mu * mu)), 0, float(-mu));
        inside += 2 * mu *
                  quadratureAlbedo(glass, wo, TransportMode::Importance, 400, 64).transmitted / n;
      }
      EXPECT_NEAR(coat.internalDiffuseReflectance(), 1 - inside, 4e-3) << "alpha " << alpha;
    }
}

// A nearly smooth coat transmits 1 - F(mu) (Fresnel), and reflects back in the internal diffuse
// reflectance that reciprocity ties to the external one: 1 - Fdr_in = (1 - Fdr_out) / eta^2,
// with Fdr_out = 2 \int F(mu) mu dmu = 0.0918 for index 1.5.
TEST(CoatingTransmittance, SmoothLimitIsFresnel) {
  const CoatingTransmittance coat(MicrofacetDistribution::GGX, 1e-4f, 1.5f);
  double fdrOut = 0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    const double mu = (k + 0.5) / n;
    float cosT;
    fdrOut += 2 * mu * fresnelDielectric(float(mu), 1.5f, &cosT) / n;
  }
  EXPECT_NEAR(fdrOut, 0.0918, 5e-4);
  for (float mu : {0.1f, 0.3f, 0.7f, 1.0f}) {
    float cosT;
    EXPECT_NEAR(coat.fromOutside(mu), 1 - fresnelDielectric(mu, 1.5f, &cosT), 2e-3) << mu;
  }
  EXPECT_NEAR(coat.internalDiffuseReflectance(), 1 - (1 - fdrOut) / 2.25, 2e-3);
}

TEST(Bsdf, CoatedDiffuseSamplingMatchesEvaluation) {
  for (MicrofacetDistribution dist :
       {MicrofacetDistribution::GGX, MicrofacetDistribution::Beckmann})
    for (float alpha : {0.02f, 0.3f})
      for (float c : {0.9f, 0.25f, -0.6f}) {
        checkSamplingConsistency(coated(dist, alpha, Spectrum(0.5f, 0.3f, 0.2f), Spectrum(1.0f)),
                                 c);
        checkSamplingConsistency(coated(dist, alpha, Spectrum(0.8f), Spectrum(0.5f), 1.3f, true),
                                 c);
      }
}

// A white base under a clear coat is a white furnace: whatever the coat does not reflect it lets
// in, the base returns, and the coat lets out in the end (Mitsuba's linear form, 1 / (1 - Fdr),
// is exactly that geometric series for rho = 1 under a smooth coat). So the coated white loses
// what the rough boundary itself loses to its microfacets' shadowing: its albedo is the rough
// dielectric's reflected plus transmitted share (quadratureAlbedo of the dielectric, importance
// form). A wrong eta^2, T or Fdr breaks that at some angle.
TEST(Bsdf, CoatedWhiteDiffuseConservesEnergy) {
  for (float eta : {1.5f, 1.2f})
    for (float alpha : {0.01f, 0.1f}) {
      const BsdfDescription white =
          coated(MicrofacetDistribution::GGX, alpha, Spectrum(1.0f), Spectrum(1.0f), eta);
      const BsdfDescription boundary = roughGlass(MicrofacetDistribution::GGX, alpha, eta);
      for (float mu : {0.95f, 0.6f, 0.3f}) {
        const Vec3f wo(std::sqrt(1 - mu * mu), 0, mu);
        const double albedo =
            quadratureAlbedo(white, wo, TransportMode::Radiance, 2000, 256).total();
        const double kept =
            quadratureAlbedo(boundary, wo, TransportMode::Importance, 2000, 256).total();
        EXPECT_NEAR(albedo, kept, 0.005) << "eta " << eta << " alpha " << alpha << " mu " << mu;
        EXPECT_LE(albedo, 1.0 + 2e-3);
      }
    }
  // The nonlinear form darkens: rho / (1 - rho Fdr) < rho / (1 - Fdr) for rho < 1.
  const Vec3f wo(0, 0, 1);
  const double linear =
      quadratureAlbedo(coated(MicrofacetDistribution::GGX, 0.1f, Spectrum(0.5f), Spectrum(0.0f)),
                       wo, TransportMode::Radiance, 1000, 128)
          .total();
  const double nonlinear = quadratureAlbedo(coated(MicrofacetDistribution::GGX, 0.1f,
                                                   Spectrum(0.5f), Spectrum(0.0f), 1.5f, true),
                                            wo, TransportMode::Radiance, 1000, 128)
                               .total();
  EXPECT_LT(nonlinear, linear - 0.05);
  EXPECT_THROW(Bsdf([] {
                 BsdfDescription d =
                     coated(MicrofacetDistribution::GGX, 0.1f, Spectrum(0.5f), Spectrum(1.0f));
                 d.coating.reset();
                 return d;
               }()),
               std::invalid_argument);
}

// A dielectric's two sides differ (the relative index flips), so mirroring its back onto its
// front would swap reflection and refraction: such a description is refused, as the loaders
// refuse Mitsuba's twosided around one.
TEST(Bsdf, RefusesATwoSidedDielectric) {
  for (auto type : {BsdfDescription::Type::Dielectric, BsdfDescription::Type::RoughDielectric}) {
    BsdfDescription d;
    d.type = type;
    EXPECT_NO_THROW(Bsdf{d});
    d.twoSided = true;
    EXPECT_THROW(Bsdf{d}, std::invalid_argument);
  }
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

// Reflection and refraction through microfacets, from outside and from inside, carrying radiance
// and importance.
TEST(Bsdf, RoughDielectricSamplingMatchesEvaluation) {
  for (MicrofacetDistribution d : {MicrofacetDistribution::Beckmann, MicrofacetDistribution::GGX}) {
    for (float alpha : {0.05f, 0.3f, 1.0f}) {
      for (float cosO : {0.9f, 0.2f, -0.5f, -0.95f}) {
        for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
          SCOPED_TRACE(testing::Message()
                       << (d == MicrofacetDistribution::GGX ? "ggx" : "beckmann") << " alpha "
                       << alpha << " cos " << cosO << " mode " << int(mode));
          checkSamplingConsistency(roughGlass(d, alpha), cosO, mode);
        }
      }
    }
  }
}

// Generalized reciprocity (Veach 1997, eq. 5.14): f(wo, wi) / eta_o^2 is symmetric, and the
// adjoint BSDF that importance uses is f with its arguments swapped.
TEST(Bsdf, RoughDielectricIsReciprocal) {
  Bsdf bsdf(roughGlass(MicrofacetDistribution::GGX, 0.4f));
  Rng rng(5, 9);
  int transmissions = 0;
  for (int i = 0; i < 2000; ++i) {
    Vec3f wo = squareToUniformSphere({rng.nextFloat(), rng.nextFloat()});
    Vec3f wi = squareToUniformSphere({rng.nextFloat(), rng.nextFloat()});
    const float etaO = wo.z > 0 ? 1.0f : 1.5f, etaI = wi.z > 0 ? 1.0f : 1.5f;
    const float f = bsdf.eval(wo, wi, TransportMode::Radiance).y;
    const float back = bsdf.eval(wi, wo, TransportMode::Radiance).y;
    EXPECT_NEAR(f / (etaO * etaO), back / (etaI * etaI), 1e-4f * f + 1e-7f);
    EXPECT_NEAR(bsdf.eval(wo, wi, TransportMode::Importance).y, back, 1e-4f * back + 1e-7f);
    transmissions += wo.z * wi.z < 0 && f > 0;
  }
  EXPECT_GT(transmissions, 150);
}

// At alpha 1e-4 the microfacet lobes are Dirac lobes within noise: the rough conductor reflects
// what the smooth one does, and the rough dielectric reflects F and transmits (1 - F), times
// (eta_o / eta_i)^2 for radiance, as the smooth one does. The rough side comes from a
// quadrature of eval(), the smooth from sample(): no code in common.
TEST(Bsdf, RoughAtTheStiffEndIsSmooth) {
  for (MicrofacetDistribution d : {MicrofacetDistribution::Beckmann, MicrofacetDistribution::GGX}) {
    BsdfDescription rough = conductor(d, 1e-4f), smooth = rough;
    smooth.type = BsdfDescription::Type::Conductor;
    for (float cosO : {0.95f, 0.5f, 0.2f}) {
      const Vec3f wo(std::sqrt(1 - cosO * cosO), 0, cosO);
      BsdfSample s;
      const float u[3] = {0.5f, 0.5f, 0.5f};
      ASSERT_TRUE(Bsdf(smooth).sample(wo, u, TransportMode::Radiance, &s));
      EXPECT_TRUE(s.delta);
      EXPECT_NEAR(quadratureAlbedo(rough, wo, TransportMode::Radiance, 2000, 256).total(),
                  s.weight.y, 2e-3 * s.weight.y)
          << "conductor, cos " << cosO;
    }
    for (float cosO : {0.95f, 0.5f, -0.5f, -0.95f}) {
      const Vec3f wo(std::sqrt(1 - cosO * cosO), 0, cosO);
      BsdfDescription glass = roughGlass(d, 1e-4f), clear = glass;
      clear.type = BsdfDescription::Type::Dielectric;
      for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
        const Albedo a = quadratureAlbedo(glass, wo, mode, 2000, 256);
        BsdfSample reflected, refracted;
        const float uR[3] = {0.0f, 0.5f, 0.5f}, uT[3] = {0.99999f, 0.5f, 0.5f};
        ASSERT_TRUE(Bsdf(clear).sample(wo, uR, mode, &reflected));
        ASSERT_TRUE(Bsdf(clear).sample(wo, uT, mode, &refracted));
        const bool tir = refracted.wi.z * wo.z > 0;
        const double r = reflected.pdf * reflected.weight.y;
        const double t = tir ? 0.0 : refracted.pdf * refracted.weight.y;
        EXPECT_NEAR(a.reflected, r, 2e-3 * r + 1e-4) << "dielectric, cos " << cosO;
        EXPECT_NEAR(a.transmitted, t, 2e-3 * t + 1e-4) << "dielectric, cos " << cosO;
      }
    }
  }
}

// The smooth conductor: one Dirac lobe, the mirror direction, weighted by the Fresnel
// reflectance (normal incidence: ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2)), from both sides when
// twosided and from the front only otherwise.
TEST(Bsdf, SmoothConductorIsAFresnelMirror) {
  BsdfDescription d;
  d.type = BsdfDescription::Type::Conductor;
  d.eta = Spectrum(0.2f, 0.9f, 1.1f);
  d.k = Spectrum(3.9f, 2.4f, 2.1f);
  d.specularReflectance = Spectrum(0.5f, 1.0f, 1.0f);
  Bsdf bsdf(d);
  const float u[3] = {0.3f, 0.7f, 0.1f};
  BsdfSample s;
  ASSERT_TRUE(bsdf.sample(Vec3f(0, 0, 1), u, TransportMode::Radiance, &s));
  EXPECT_TRUE(s.delta);
  EXPECT_EQ(s.pdf, 1.0f);
  EXPECT_NEAR(s.weight.x, 0.5f * (0.64f + 15.21f) / (1.44f + 15.21f), 1e-5f);
  EXPECT_NEAR(s.wi.z, 1.0f, 1e-7f);
  const Vec3f wo = normalize(Vec3f(0.3f, -0.4f, 0.5f));
  ASSERT_TRUE(bsdf.sample(wo, u, TransportMode::Importance, &s));
  EXPECT_NEAR(length(s.wi - Vec3f(-wo.x, -wo.y, wo.z)), 0.0f, 1e-6f);
  EXPECT_EQ(bsdf.eval(wo, s.wi, TransportMode::Radiance).y, 0.0f);  // a Dirac lobe
  EXPECT_EQ(bsdf.pdf(wo, s.wi), 0.0f);
  EXPECT_FALSE(bsdf.sample(-wo, u, TransportMode::Radiance, &s));  // one-sided: the back is black
  d.twoSided = true;
  ASSERT_TRUE(Bsdf(d).sample(-wo, u, TransportMode::Radiance, &s));
  EXPECT_NEAR(length(s.wi - Vec3f(wo.x, wo.y, -wo.z)), 0.0f, 1e-6f);
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

}  // namespace
}  // namespace farm

namespace farm {
namespace {

// Stiff cases of docs/design.md: roughness from 1e-4 to 1, indices of refraction near one and very
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
  // The rough dielectric at both ends of roughness and index, from outside and inside.
  for (float alpha : {1e-4f, 1.0f}) {
    for (float ior : {1.0001f, 1.8f, 10.0f}) {
      Bsdf bsdf(roughGlass(MicrofacetDistribution::GGX, alpha, ior));
      for (float cosO : {1.0f, 0.5f, 1e-3f, -0.5f, -1e-3f}) {
        Vec3f wo(std::sqrt(std::max(0.0f, 1 - cosO * cosO)), 0, cosO);
        for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
          double sum = 0, sumSq = 0;
          const int n = 5000;
          for (int i = 0; i < n; ++i) {
            float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
            BsdfSample s;
            if (!bsdf.sample(wo, u, mode, &s)) continue;
            ASSERT_TRUE(isValidRadiance(s.weight)) << alpha << " " << ior << " " << cosO;
            ASSERT_TRUE(std::isfinite(s.pdf) && s.pdf > 0);
            ASSERT_TRUE(isValidRadiance(bsdf.eval(wo, s.wi, mode)));
            ASSERT_TRUE(std::isfinite(bsdf.pdf(wo, s.wi)));
            sum += s.weight.y;
            sumSq += double(s.weight.y) * s.weight.y;
          }
          // Energy conservation for the adjoint's albedo (see checkSamplingConsistency), up to
          // the estimate's own standard error: a lossless interface's weights scatter around 1.
          const double mean = sum / n, se = std::sqrt((sumSq / n - mean * mean) / n);
          if (mode == TransportMode::Importance) {
            EXPECT_LE(mean, 1.0 + 4.4 * se + 1e-6) << alpha << " " << ior << " " << cosO;
          }
        }
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
void checkDiracLobes(const BsdfDescription& desc, bool refracts) {
  Bsdf bsdf(desc);
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
  if (refracts) {
    EXPECT_GT(refractions, 1000);
  } else {
    EXPECT_EQ(refractions, 0);
  }
}

TEST(DiracLobes, SpecularLobeAgreesWithSample) {
  BsdfDescription glass;
  glass.type = BsdfDescription::Type::Dielectric;
  glass.intIOR = 1.5f;
  glass.extIOR = 1.0f;
  checkDiracLobes(glass, true);
  BsdfDescription mirror;
  mirror.type = BsdfDescription::Type::Conductor;
  mirror.eta = Spectrum(0.2f, 0.9f, 1.1f);
  mirror.k = Spectrum(3.9f, 2.4f, 2.1f);
  mirror.twoSided = true;
  checkDiracLobes(mirror, false);
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
