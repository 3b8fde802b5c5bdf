// The phase function against its own normalization and its first moment, and the media's
// distance sampling and transmittance estimators against integrals computed without them (the
// closed form for a homogeneous segment, a fine midpoint rule along a grid).
#include "common/scene/medium.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/math/statistics.h"
#include "common/sampling/rng.h"

namespace farm {
namespace {

struct Accumulator {
  std::vector<double> x;
  void add(double v) { x.push_back(v); }
  MeanEstimate estimate() const { return meanOfIndependent(x); }
};

void expectWithin(const MeanEstimate& e, double expected, const std::string& what) {
  EXPECT_NEAR(e.mean, expected, 5 * e.standardError + 1e-7) << what;
}

TEST(HenyeyGreenstein, IntegratesToOneAndSamplesItsOwnDensity) {
  const Vec3f wo = normalize(Vec3f(0.3f, -0.2f, 0.9f));
  for (float g : {-0.6f, 0.0f, 0.3f, 0.9f}) {
    const HenyeyGreenstein phase(g);
    // The integral over the sphere by a midpoint rule in (cos, phi) about a pole away from wo.
    double integral = 0;
    const int n = 800;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < 64; ++j) {
        const double c = -1 + (i + 0.5) * 2.0 / n, phi = (j + 0.5) * 2 * kPi / 64;
        const double s = std::sqrt(1 - c * c);
        const Vec3f wi(float(s * std::cos(phi)), float(s * std::sin(phi)), float(c));
        integral += phase.eval(wo, wi) * (2.0 / n) * (2 * kPi / 64);
      }
    EXPECT_NEAR(integral, 1.0, 2e-3) << "g " << g;

    // Samples: the density they report is eval's, and their mean cosine with the direction of
    // travel (-wo) is g, the defining moment of the Henyey-Greenstein function.
    Rng rng(7, uint64_t(1000 * (g + 1)));
    Accumulator cosine;
    for (int k = 0; k < 200000; ++k) {
      float pdf;
      const Vec3f wi = phase.sample(wo, {rng.nextFloat(), rng.nextFloat()}, &pdf);
      ASSERT_NEAR(length(wi), 1.0f, 1e-4f);
      ASSERT_NEAR(pdf, phase.eval(wo, wi), 1e-3f * pdf + 1e-6f);
      cosine.add(-dot(wo, wi));
    }
    expectWithin(cosine.estimate(), g, "mean cosine for g " + std::to_string(g));
  }
}

class RngSampler final : public Sampler {
 public:
  explicit RngSampler(uint64_t seed) : rng_(seed, 3) {}
  float next(SampleStream) override { return rng_.nextFloat(); }

 private:
  Rng rng_;
};

// For f(t) = exp(-k t) along the segment and a value F at its end, the volume rendering
// equation's integral of sigma_s(t) T(t) f(t) dt + T(L) F, which sampleInteraction estimates
// by weight * (scattered ? f(t) : F).
void expectInteractionUnbiased(const Medium& medium, const Vec3f& o, const Vec3f& d, float L,
                               const Spectrum& expected, double k, double F,
                               const std::string& what) {
  RngSampler sampler(11);
  Accumulator channels[3];
  for (int i = 0; i < 400000; ++i) {
    const MediumInteraction m = medium.sampleInteraction(o, d, L, sampler, kCameraStream);
    const double value = m.scattered ? std::exp(-k * m.t) : F;
    if (m.scattered) {
      ASSERT_TRUE(m.t >= 0 && m.t < L) << what;
    }
    for (int c = 0; c < 3; ++c) channels[c].add(m.weight[c] * value);
  }
  for (int c = 0; c < 3; ++c)
    expectWithin(channels[c].estimate(), expected[c], what + " channel " + std::to_string(c));
}

TEST(Medium, HomogeneousDistanceSamplingIsUnbiased) {
  MediumDescription desc;
  desc.sigmaA = Spectrum(0.2f, 0.5f, 0.0f);
  desc.sigmaS = Spectrum(0.6f, 0.1f, 0.9f);
  const Medium medium(desc);
  const double k = 0.7, F = 0.4;
  for (float L : {0.5f, 2.0f, 6.0f}) {
    Spectrum expected;
    for (int c = 0; c < 3; ++c) {
      const double st = double(desc.sigmaA[c]) + desc.sigmaS[c];
      // sigma_s int_0^L exp(-(st + k) t) dt + exp(-st L) F
      expected[c] =
          float(desc.sigmaS[c] * (1 - std::exp(-(st + k) * L)) / (st + k) + std::exp(-st * L) * F);
    }
    expectInteractionUnbiased(medium, Vec3f(0.0f), Vec3f(0, 0, 1), L, expected, k, F,
                              "L " + std::to_string(L));
    RngSampler sampler(1);
    const Spectrum T = medium.transmittance(Vec3f(0.0f), Vec3f(0, 0, 1), L, sampler, kCameraStream);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(T[c], std::exp(-(desc.sigmaA[c] + desc.sigmaS[c]) * L), 1e-6);
  }
}

// A 6 x 5 x 4 grid of uneven densities over a box [-1, 2] x [0, 1] x [0, 2], crossed obliquely.
MediumDescription gridDescription(bool cellCentred) {
  MediumDescription desc;
  desc.type = MediumDescription::Type::Grid;
  desc.sigmaA = Spectrum(0.5f, 1.0f, 1.75f);  // sigma_t 2, a coloured albedo
  desc.sigmaS = Spectrum(1.5f, 1.0f, 0.25f);
  desc.nx = 6, desc.ny = 5, desc.nz = 4;
  Rng rng(3, 4);
  for (int i = 0; i < desc.nx * desc.ny * desc.nz; ++i)
    desc.density.push_back(rng.nextFloat() < 0.3f ? 0.0f : 2 * rng.nextFloat());
  desc.cellCentred = cellCentred;
  desc.worldToGrid =
      Matrix4::scale(Vec3f(1 / 3.0f, 1.0f, 0.5f)) * Matrix4::translate(Vec3f(1.0f, 0.0f, 0.0f));
  return desc;
}

TEST(Medium, GridDeltaAndRatioTrackingAgreeWithTheMarchedIntegral) {
  for (bool centred : {true, false}) {
    const MediumDescription desc = gridDescription(centred);
    ASSERT_EQ(mediumProblem(desc), "");
    const Medium medium(desc);
    const Vec3f o(-2.0f, 0.1f, 0.3f), d = normalize(Vec3f(1.0f, 0.2f, 0.4f));
    const float L = 4.5f;  // enters the box, and leaves it through its top
    const double k = 0.3, F = 0.8;
    // The integral by the midpoint rule at 20000 steps: sigma_s(t) T(t) f(t) along, T(L) F.
    const int steps = 20000;
    const double dt = double(L) / steps;
    double depth = 0;
    Spectrum expected(0.0f);
    const float sigmaT = desc.sigmaA.x + desc.sigmaS.x;
    for (int i = 0; i < steps; ++i) {
      const double t = (i + 0.5) * dt;
      const double rho = medium.density(o + d * float(t));
      const double T = std::exp(-(depth + 0.5 * rho * sigmaT * dt));
      for (int c = 0; c < 3; ++c)
        expected[c] += float(rho * desc.sigmaS[c] * T * std::exp(-k * t) * dt);
      depth += rho * sigmaT * dt;
    }
    const double TL = std::exp(-depth);
    ASSERT_GT(depth, 0.5) << "the segment must cross a real amount of medium";
    ASSERT_NEAR(medium.marchedTransmittance(o, d, L, steps).x, TL, 1e-4);
    for (int c = 0; c < 3; ++c) expected[c] += float(TL * F);
    const std::string what = centred ? "cell-centred" : "corner-sampled";
    expectInteractionUnbiased(medium, o, d, L, expected, k, F, what);

    RngSampler sampler(5);
    Accumulator ratio;
    for (int i = 0; i < 200000; ++i)
      ratio.add(medium.transmittance(o, d, L, sampler, kCameraStream).x);
    expectWithin(ratio.estimate(), TL, what + " ratio tracking");
  }
}

// Path-space MLT's free flights: the density freeFlightDensity gives is the one
// sampleFreeFlight draws from, in a homogeneous medium of three extinctions and in the grid
// (passing: its probability; landing: its integral over each of 12 bins of the segment, by
// the midpoint rule at 200 points a bin), for a segment that ends inside the grid's box and one
// that leaves it. Along the same ray from a point further back (a flight that started before a
// null boundary), the density of the same point is the same: the grid's steps belong to the
// ray's chord through the box, not to the segment.
TEST(Medium, FreeFlightDensityIsTheSamplersOwn) {
  MediumDescription homogeneous;
  homogeneous.sigmaA = Spectrum(0.2f, 0.5f, 0.0f);
  homogeneous.sigmaS = Spectrum(0.6f, 1.1f, 0.3f);
  const Medium media[2] = {Medium(homogeneous), Medium(gridDescription(true))};
  const Vec3f o(-2.0f, 0.1f, 0.3f), d = normalize(Vec3f(1.0f, 0.2f, 0.4f));
  for (const Medium& medium : media) {
    for (float L : {2.5f, 4.5f}) {
      const std::string what =
          std::string(medium.isHomogeneous() ? "homogeneous" : "grid") + ", L " + std::to_string(L);
      constexpr int kBins = 12, kSamples = 400000;
      std::vector<Accumulator> bins(kBins);
      Accumulator passed;
      Rng rng(9, 2);
      for (int i = 0; i < kSamples; ++i) {
        const float t = medium.sampleFreeFlight(o, d, L, rng.nextFloat(), rng.nextFloat());
        ASSERT_GE(t, 0.0f);
        ASSERT_LE(t, L);
        passed.add(t >= L ? 1.0 : 0.0);
        const int bin = t >= L ? -1 : std::min(int(t / L * kBins), kBins - 1);
        for (int b = 0; b < kBins; ++b) bins[size_t(b)].add(b == bin ? 1.0 : 0.0);
      }
      expectWithin(passed.estimate(), medium.freeFlightDensity(o, d, L, false), what + " passing");
      double total = medium.freeFlightDensity(o, d, L, false);
      for (int b = 0; b < kBins; ++b) {
        double integral = 0;
        const double width = double(L) / kBins;
        for (int j = 0; j < 200; ++j) {
          const float t = float((b + (j + 0.5) / 200) * width);
          integral += medium.freeFlightDensity(o, d, t, true) * width / 200;
        }
        total += integral;
        expectWithin(bins[size_t(b)].estimate(), integral, what + " bin " + std::to_string(b));
      }
      EXPECT_NEAR(total, 1.0, 2e-3) << what << ": the densities integrate to one";
    }
  }
  const Medium& grid = media[1];
  for (float t : {2.2f, 2.9f, 3.4f}) {
    const float back = 0.7f;
    EXPECT_NEAR(grid.freeFlightDensity(o - d * back, d, t + back, true) /
                    grid.freeFlightDensity(o - d * back, d, back, false),
                grid.freeFlightDensity(o, d, t, true), 1e-4 * grid.freeFlightDensity(o, d, t, true))
        << "at " << t;
  }
}

TEST(Medium, GridDensityInterpolatesItsSamples) {
  MediumDescription desc = gridDescription(false);
  const Medium corner(desc);
  // Corner-sampled: sample (i, j, k) sits at (i / (nx - 1), ...) of the unit cube.
  const Matrix4 gridToWorld = desc.worldToGrid.inverse();
  for (int i : {0, 2, 5})
    for (int k : {0, 3}) {
      const Vec3f q(float(i) / 5, 0.25f, float(k) / 3);
      EXPECT_NEAR(corner.density(gridToWorld.applyPoint(q)),
                  desc.density[size_t((k * desc.ny + 1) * desc.nx + i)], 1e-4f);
    }
  desc.cellCentred = true;
  const Medium centred(desc);
  const Vec3f q((2 + 0.5f) / 6, (1 + 0.5f) / 5, (3 + 0.5f) / 4);
  EXPECT_NEAR(centred.density(gridToWorld.applyPoint(q)),
              desc.density[size_t((3 * desc.ny + 1) * desc.nx + 2)], 1e-4f);
  EXPECT_EQ(centred.density(Vec3f(5.0f, 0.5f, 0.5f)), 0.0f);  // outside the box
}

TEST(Medium, ProblemsAreNamed) {
  MediumDescription bad = gridDescription(true);
  bad.sigmaS = Spectrum(1.0f, 2.0f, 1.0f);
  EXPECT_NE(mediumProblem(bad).find("same in every channel"), std::string::npos);
  bad = gridDescription(true);
  bad.density.pop_back();
  EXPECT_NE(mediumProblem(bad).find("values, not"), std::string::npos);
  bad = gridDescription(true);
  bad.density[3] = NAN;
  EXPECT_NE(mediumProblem(bad).find("finite"), std::string::npos);
  MediumDescription h;
  h.g = 1;
  EXPECT_NE(mediumProblem(h).find("(-1, 1)"), std::string::npos);
  h.g = 0;
  h.sigmaA = Spectrum(-1.0f);
  EXPECT_NE(mediumProblem(h).find(">= 0"), std::string::npos);
}

}  // namespace
}  // namespace farm
