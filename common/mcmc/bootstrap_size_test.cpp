// The bootstrap's size: within its time share of the job, large enough that Z's error hides in
// an average pixel's, and the same for the same job on every run.
#include "common/mcmc/bootstrap_size.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "common/mcmc/bootstrap.h"
#include "common/render/render_job.h"
#include "common/sampling/rng.h"

namespace farm {
namespace {

// Share of the job's cost the candidates take, in units of the algorithm's work.
double timeShare(Algorithm a, int64_t candidates, int64_t work) {
  const double cost = bootstrapCandidateCost(a) * double(candidates);
  return cost / (cost + double(work));
}

TEST(BootstrapSize, TakesItsShareOfTheJobWhereZIsWellMeasured) {
  // 1920x1080 at 64 mutations per pixel (ERPT, whose samples cost far more than a candidate,
  // at 256x256 and 16), a low-variance scene: the time share sets the count.
  for (Algorithm a : {Algorithm::PSSMLT, Algorithm::MMLT, Algorithm::MLT, Algorithm::ERPT}) {
    const int64_t pixels = a == Algorithm::ERPT ? 256 * 256 : 1920 * 1080;
    const int64_t work = pixels * (a == Algorithm::ERPT ? 16 : 64);
    const BootstrapSize size = bootstrapSize(a, work, pixels, 0.25);
    EXPECT_EQ(size.candidates, size.forTime) << algorithmName(a);
    EXPECT_GT(size.forTime, size.forError) << algorithmName(a);
    const double share = timeShare(a, size.candidates, work);
    EXPECT_LE(share, kBootstrapShare) << algorithmName(a);
    EXPECT_GT(share, 0.98 * kBootstrapShare) << algorithmName(a);
  }
}

TEST(BootstrapSize, KeepsZsErrorWithinAThirdOfAnAveragePixels) {
  // A small film at many mutations per pixel and a scene whose candidates vary a lot: Z's error
  // asks for more than the time share allows, and wins.
  const int64_t pixels = 64 * 64, perPixel = 4096, work = pixels * perPixel;
  const double v = 10.0 * 10.0;  // candidates' relative variance
  const BootstrapSize size = bootstrapSize(Algorithm::PSSMLT, work, pixels, v);
  EXPECT_GT(size.forError, size.forTime);
  EXPECT_EQ(size.candidates, size.forError);
  const double zError = std::sqrt(v / double(size.candidates));
  EXPECT_LE(zError, (1.0 / 3.0) / std::sqrt(double(perPixel)));
  EXPECT_GT(zError, 0.99 * (1.0 / 3.0) / std::sqrt(double(perPixel)));  // and no more than that
}

TEST(BootstrapSize, ThePilotTakesTheTimeShareWithinItsBounds) {
  // A job whose share affords 2048 candidates gets a pilot of 2048; smaller ones the floor,
  // larger ones (and time budgets, whose work is unknown) the full pilot.
  // (2048.5 candidates' worth, so that rounding cannot tip the count either way.)
  const int64_t work = int64_t(2048.5 * 64 * (1 - kBootstrapShare) / kBootstrapShare);
  EXPECT_EQ(bootstrapPilot(Algorithm::MLT, work), 2048);
  EXPECT_LE(timeShare(Algorithm::MLT, 2048, work), kBootstrapShare);
  EXPECT_EQ(bootstrapPilot(Algorithm::MLT, work / 4), kBootstrapPilotFloor);
  EXPECT_EQ(bootstrapPilot(Algorithm::MLT, work * 4), kBootstrapPilot);
  EXPECT_EQ(bootstrapPilot(Algorithm::MLT, 0), kBootstrapPilot);
  // The count never goes below the pilot: a low-variance job of that size takes it.
  EXPECT_EQ(bootstrapSize(Algorithm::MLT, work, 256 * 256, 1e-6).candidates, 2048);
}

TEST(BootstrapSize, StaysWithinThePilotAndTheCeiling) {
  EXPECT_EQ(bootstrapSize(Algorithm::MLT, 1000, 100, 1.0).candidates, kBootstrapPilotFloor);
  EXPECT_EQ(bootstrapSize(Algorithm::PSSMLT, int64_t(1) << 40, int64_t(1) << 22, 1.0).candidates,
            kBootstrapMaxCandidates);
  // A variance that is not a number asks for nothing (the time share still holds).
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const BootstrapSize size = bootstrapSize(Algorithm::PSSMLT, int64_t(1) << 30, 1 << 20, nan);
  EXPECT_EQ(size.forError, 0);
  EXPECT_EQ(size.candidates, size.forTime);
  // Algorithms without a bootstrap have no candidate cost.
  EXPECT_EQ(bootstrapCandidateCost(Algorithm::PathTracing), 0.0);
  EXPECT_EQ(bootstrapCandidateCost(Algorithm::Bidirectional), 0.0);
}

// The whole bootstrap of a job that leaves the count to it: the count is what bootstrapSize
// asks for from the pilot's variance, the same on a second run, and Z agrees with that of a
// bootstrap sixteen times larger within their combined standard error.
TEST(BootstrapSize, AJobsBootstrapIsSizedToIt) {
  RenderSettings settings;
  settings.algorithm = Algorithm::PSSMLT;
  settings.width = 64;
  settings.height = 64;
  settings.mutationsPerPixel = 256;
  settings.numChains = 8;
  auto scene = loadScene(std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml", settings);
  RenderJob job(scene, settings, "sized");
  const BootstrapResult b = job.bootstrap();
  const int64_t work = job.plannedWork();
  ASSERT_EQ(work, 64 * 64 * 256);
  BootstrapCandidates pilot = generateCandidates(*scene, settings.algorithm, -1, settings.seed,
                                                 bootstrapPilot(settings.algorithm, work));
  ASSERT_GE(pilot.nonZero, kBootstrapPilotLight);
  const BootstrapSize size =
      bootstrapSize(settings.algorithm, work, 64 * 64, pilot.relativeVariance());
  EXPECT_EQ(b.candidates, size.candidates);
  EXPECT_EQ(b.candidatesForTime, size.forTime);
  EXPECT_EQ(b.candidatesForError, size.forError);
  EXPECT_LE(timeShare(settings.algorithm, b.candidates, work), kBootstrapShare);

  const BootstrapResult again = job.bootstrap();
  EXPECT_EQ(again.candidates, b.candidates);
  EXPECT_EQ(again.normalization, b.normalization);
  EXPECT_EQ(again.seedSamples, b.seedSamples);

  RenderSettings large = settings;
  large.bootstrapSamples = 16 * b.candidates;
  const BootstrapResult reference = RenderJob(scene, large, "large").bootstrap();
  EXPECT_EQ(reference.candidates, 16 * b.candidates);
  // The first candidates are shared, so the difference's error is below this sum's.
  const double tolerance = 4 * std::hypot(b.normalizationStdError, reference.normalizationStdError);
  EXPECT_NEAR(b.normalization, reference.normalization, tolerance);
}

// Z is the mean of candidates whose count the pilot chose; where light comes in rare bright
// candidates it must still be unbiased. An integrand whose value is 8192 with chance 1 / 8192 and
// 1 otherwise (half of Z in the rare ones): a pilot of 4096 meets a bright candidate in 39% of the
// jobs, measures a relative variance near 1000 and asks for up to 65k candidates, and in the
// others measures none and stops at the time share's 13.8k. Pooled with the candidates it sized
// (as until December 2026), the pilot's bright ones were diluted where they were and its dark ones
// kept where they were: Z came out 7.1% low over these jobs, 10.7 standard errors. Z over 2000
// jobs, each with its own stream, must meet the exact mean within 4 standard errors of their
// spread.
TEST(BootstrapSize, ZIsUnbiasedThoughThePilotSizedIt) {
  constexpr double kBright = 8192, kChance = 1.0 / 8192;
  const double exact = (1 - kChance) + kBright * kChance;
  BootstrapRequest request;
  request.algorithm = Algorithm::PSSMLT;
  request.pixels = int64_t(1) << 16;
  request.plannedWork = 4 * request.pixels;
  constexpr int kJobs = 2000;
  double sum = 0, sumSquares = 0;
  int64_t fewest = std::numeric_limits<int64_t>::max(), most = 0;
  for (int job = 0; job < kJobs; ++job) {
    SizedCandidates sized;
    const auto evaluate = [&](int64_t index) {
      Rng rng(uint64_t(job), streamId(0xb1a5, uint64_t(index)));
      return rng.nextDouble() < kChance ? kBright : 1.0;
    };
    ASSERT_TRUE(drawSizedCandidates(evaluate, request, &sized));
    EXPECT_EQ(sized.pilot, kBootstrapPilot);
    EXPECT_EQ(sized.candidates.firstIndex, sized.pilot);
    const double z = sized.candidates.mean;
    sum += z;
    sumSquares += z * z;
    fewest = std::min(fewest, int64_t(sized.candidates.contributions.size()));
    most = std::max(most, int64_t(sized.candidates.contributions.size()));
  }
  const double mean = sum / kJobs;
  const double standardError =
      std::sqrt(std::max(0.0, sumSquares / kJobs - mean * mean) / (kJobs - 1));
  std::printf("Z over %d jobs %.4f +- %.4f, exact %.4f (%+.2f%%); candidates %lld .. %lld\n", kJobs,
              mean, standardError, exact, 100 * (mean / exact - 1), (long long)fewest,
              (long long)most);
  EXPECT_NEAR(mean, exact, 4 * standardError);
  EXPECT_LT(standardError, 0.01 * exact) << "too few jobs to see a bias of a few percent";
  // The pilot did size them: else this would test a fixed count.
  EXPECT_GT(most, 4 * fewest);
}

}  // namespace
}  // namespace farm
