// Planning a job: the parts a plan leaves out change nothing but the asking (the same chain,
// the same image, the same rays), auto takes the plan's only candidate where there is one,
// and the pilot ranks candidates by their estimated error times time.
#include "common/render/algorithm_pilot.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "common/render/local_render.h"
#include "common/scene/scene.h"

namespace farm {
namespace {

const std::string kShared = FARM_SHARED_DIR;

std::shared_ptr<Scene> load(const std::string& path, int side) {
  RenderSettings settings;
  settings.autoAlgorithm = true;
  settings.width = settings.height = side;
  return loadScene(path, settings);
}

// mlt on the Cornell box, with and without the plan: the multi-chain and manifold
// perturbations never apply to a path without specular vertices, so at zero weight the chain
// draws the same numbers and takes the same steps. A plan that left out a mutation that does
// apply (the caustic perturbation, which moves D D E paths) would change the image here.
TEST(PlanJob, LeavingOutTheSpecularMutationsChangesNothingButTheAsking) {
  std::shared_ptr<Scene> scene = load(kShared + "/scenes/cornell-box/scene.xml", 48);
  RenderSettings asked;
  asked.algorithm = Algorithm::MLT;
  asked.width = asked.height = 48;
  asked.mutationsPerPixel = 32;
  asked.numChains = 8;
  asked.seed = 3;
  RenderSettings planned = asked, kept = asked;
  const RenderPlan plan = planJob(scene, &planned);
  kept.ignorePlan = true;
  const RenderPlan notApplied = planJob(scene, &kept);
  EXPECT_TRUE(plan.applied);
  EXPECT_FALSE(notApplied.applied);
  EXPECT_EQ(planned.mutationMix.multiChainPerturbation, 0);
  EXPECT_EQ(planned.mutationMix.manifoldPerturbation, 0);
  EXPECT_EQ(kept.mutationMix, MutationMix());

  const LocalRenderResult a = renderLocally(RenderJob(scene, planned, "planned"));
  const LocalRenderResult b = renderLocally(RenderJob(scene, kept, "kept"));
  EXPECT_EQ(a.work, b.work);
  EXPECT_EQ(a.rays, b.rays);
  ASSERT_EQ(a.image.rgb.size(), b.image.rgb.size());
  for (size_t i = 0; i < a.image.rgb.size(); ++i)
    ASSERT_EQ(a.image.rgb[i], b.image.rgb[i]) << "value " << i;
  EXPECT_EQ(a.tallies.count("multichain"), 0u);
  EXPECT_EQ(a.tallies.count("manifold"), 0u);
  EXPECT_GT(a.tallies.count("caustic"), 0u) << "the caustic perturbation is kept";
}

TEST(PlanJob, AutoTakesTheOnlyCandidateWithoutAPilot) {
  std::shared_ptr<Scene> scene = load(kShared + "/scenes/water-caustic/scene.xml", 32);
  RenderSettings settings;
  settings.autoAlgorithm = true;
  settings.width = settings.height = 32;
  const RenderPlan plan = planJob(scene, &settings);
  EXPECT_EQ(settings.algorithm, Algorithm::MLT);
  EXPECT_FALSE(settings.autoAlgorithm);
  EXPECT_TRUE(plan.automatic);
  EXPECT_TRUE(plan.pilot.empty());
  EXPECT_EQ(settings.mutationMix, MutationMix());
}

// The Markov chains under specular-diffuse-specular light, much (water-caustic) or little
// (veach-bidir), get the plan's chain count unless the settings name one, and keep their own
// with --no-plan; path tracing there, and every algorithm on scenes without such light, keeps
// the default.
TEST(PlanJob, MarkovChainsUnderSpecularDiffuseSpecularLightTakeThePlansChains) {
  std::shared_ptr<Scene> water = load(kShared + "/scenes/water-caustic/scene.xml", 32);
  RenderSettings settings;
  settings.algorithm = Algorithm::MLT;
  settings.width = settings.height = 32;
  RenderSettings asked = settings, kept = settings, pssmlt = settings, pt = settings,
                 cornell = settings, mmlt = settings, bidirPt = settings, mis = settings,
                 ajar = settings;
  asked.numChains = 256;
  kept.ignorePlan = true;
  pssmlt.algorithm = Algorithm::PSSMLT;
  pt.algorithm = bidirPt.algorithm = Algorithm::PathTracing;
  mmlt.algorithm = mis.algorithm = Algorithm::MMLT;
  const RenderPlan plan = planJob(water, &settings);
  EXPECT_EQ(settings.numChains, kSdsChains);
  EXPECT_EQ(plan.chains, kSdsChains);
  bool named = false;
  for (const std::string& line : plan.describe())
    named |= line.rfind("chains: " + std::to_string(kSdsChains) + " (specular-diffuse", 0) == 0;
  EXPECT_TRUE(named) << "the plan names the chains and why";
  const RenderPlan requested = planJob(water, &asked);
  EXPECT_EQ(asked.numChains, 256);
  EXPECT_EQ(requested.chains, 256);
  EXPECT_NE(requested.chainsReason.find("requested"), std::string::npos);
  planJob(water, &kept);
  EXPECT_EQ(kept.numChains, kDefaultChains) << "--no-plan keeps the default";
  planJob(water, &pssmlt);
  EXPECT_EQ(pssmlt.numChains, kSdsChains);
  planJob(water, &pt);
  EXPECT_EQ(pt.numChains, kDefaultChains) << "work units, not chains";
  std::shared_ptr<Scene> bidir = load(kShared + "/scenes/veach-bidir/scene.xml", 32);
  const RenderPlan little = planJob(bidir, &mmlt);
  EXPECT_EQ(mmlt.numChains, kSdsChains);
  EXPECT_EQ(little.chainsReason.rfind("some specular-diffuse-specular light", 0), 0u)
      << little.chainsReason;
  planJob(bidir, &bidirPt);
  EXPECT_EQ(bidirPt.numChains, kDefaultChains);
  const RenderPlan other = planJob(load(kShared + "/scenes/cornell-box/scene.xml", 32), &cornell);
  EXPECT_EQ(cornell.numChains, kDefaultChains);
  EXPECT_EQ(other.chains, 0);
  planJob(load(kShared + "/scenes/veach-mis/scene.xml", 32), &mis);
  EXPECT_EQ(mis.numChains, kDefaultChains) << "specular-free";
  planJob(load(kShared + "/scenes/veach-ajar/scene.pbrt", 32), &ajar);
  EXPECT_EQ(ajar.numChains, kDefaultChains) << "specular, but no such light";
  // And the job seeds that many chains.
  settings.mutationsPerPixel = 2;
  settings.bootstrapSamples = 1 << 12;
  RenderJob job(water, settings, "water");
  EXPECT_EQ(job.planChains(job.bootstrap()).size(), size_t(kSdsChains));
}

// On veach-bidir, whose light comes mostly through a lamp's small bulb, path tracing's error
// is tens of times bidirectional path tracing's (docs/plan.md): a pilot of half a second
// each ranks bdpt first, and says so with its figures.
TEST(PlanJob, ThePilotRanksByEstimatedErrorTimesTime) {
  std::shared_ptr<Scene> scene = load(kShared + "/scenes/veach-bidir/scene.xml", 48);
  RenderSettings settings;
  settings.width = settings.height = 48;
  const std::vector<PilotFigure> figures =
      runPilot(scene, settings, {Algorithm::PathTracing, Algorithm::Bidirectional}, 0.5);
  ASSERT_EQ(figures.size(), 2u);
  EXPECT_EQ(figures[0].algorithm, Algorithm::Bidirectional);
  for (const PilotFigure& f : figures) {
    EXPECT_TRUE(f.failure.empty()) << f.failure;
    EXPECT_GT(f.estimatedRelMse, 0) << algorithmName(f.algorithm);
    EXPECT_GT(f.seconds, 0.2) << algorithmName(f.algorithm);
    EXPECT_LT(f.seconds, 2.0) << algorithmName(f.algorithm) << ": the deadline is kept";
    EXPECT_DOUBLE_EQ(f.score, f.estimatedRelMse * f.seconds);
  }
  EXPECT_GT(figures[1].score, 3 * figures[0].score);

  // A candidate that cannot render says why and sorts last.
  const std::vector<PilotFigure> cancelled =
      runPilot(scene, settings, {Algorithm::Bidirectional}, 0.5, [] { return false; });
  EXPECT_TRUE(cancelled.empty());
}

TEST(PlanJob, ABudgetTooShortForAPilotTakesTheFirstCandidate) {
  std::shared_ptr<Scene> scene = load(kShared + "/scenes/cornell-box/scene.xml", 32);
  RenderSettings settings;
  settings.autoAlgorithm = true;
  settings.pilot = true;
  settings.width = settings.height = 32;
  settings.timeBudgetSeconds = 1;
  const RenderPlan plan = planJob(scene, &settings);
  EXPECT_TRUE(plan.pilot.empty());
  ASSERT_GT(plan.shortlist.size(), 1u);
  EXPECT_EQ(settings.algorithm, plan.shortlist.front());
  EXPECT_NE(plan.why.find("no pilot: 10% of the budget"), std::string::npos) << plan.why;
  EXPECT_FALSE(settings.pilot) << "the planned settings have nothing left to pilot";
}

// Without --pilot, auto renders the plan's first candidate at once, whatever the budget: on the
// corpus's tuning half the pilot cost more than its picks saved (docs/corpus.md).
TEST(PlanJob, AutoWithoutThePilotRendersThePlansFirstCandidate) {
  std::shared_ptr<Scene> scene = load(kShared + "/scenes/cornell-box/scene.xml", 32);
  RenderSettings settings;
  settings.autoAlgorithm = true;
  settings.width = settings.height = 32;
  settings.timeBudgetSeconds = 30;
  const auto start = std::chrono::steady_clock::now();
  const RenderPlan plan = planJob(scene, &settings);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_GT(plan.shortlist.size(), 1u);
  EXPECT_TRUE(plan.pilot.empty());
  EXPECT_EQ(settings.algorithm, plan.shortlist.front());
  EXPECT_FALSE(settings.autoAlgorithm);
  EXPECT_NE(plan.why.find("no pilot (--pilot runs one)"), std::string::npos) << plan.why;
  // A pilot would take 3 s (10% of 30 s); the plan's probes alone take a fraction of that.
  EXPECT_LT(seconds, 2.0);

  RenderSettings bad;
  bad.pilot = true;
  EXPECT_NE(bad.validate().find("--pilot"), std::string::npos) << "--pilot without auto";
}

TEST(PlanJob, ThePilotOverrulesTheFirstCandidateOnlyByAMargin) {
  auto figure = [](Algorithm a, double score) {
    PilotFigure f;
    f.algorithm = a;
    f.score = score;
    f.estimatedRelMse = score;
    return f;
  };
  const Algorithm bdpt = Algorithm::Bidirectional, pt = Algorithm::PathTracing;
  EXPECT_EQ(pilotPick(bdpt, {figure(pt, 0.6), figure(bdpt, 1.0)}), bdpt) << "within the margin";
  EXPECT_EQ(pilotPick(bdpt, {figure(pt, 0.4), figure(bdpt, 1.0)}), pt) << "clearly better";
  EXPECT_EQ(pilotPick(bdpt, {figure(bdpt, 0.4), figure(pt, 1.0)}), bdpt);
  PilotFigure failed = figure(bdpt, -1);
  failed.failure = "no light";
  EXPECT_EQ(pilotPick(bdpt, {figure(pt, 0.9), failed}), pt) << "the first failed";
  EXPECT_EQ(pilotPick(bdpt, {}), bdpt);
}

// Where auto renders bdpt with a time budget, a pilot of a tenth of it places the samples by
// bdpt's error (PixelAllocation::byError), and the plan says so; a job of counts keeps uniform
// sampling (its seed's image stays the same), as does a budget too short for a pilot.
TEST(PlanJob, AutoPlacesBidirectionalSamplesByAPilotsError) {
  // A box of smoke, which the plan renders with bdpt.
  std::shared_ptr<Scene> scene = load(std::string(FARM_TEST_DATA_DIR) + "/smoky-box/scene.xml", 32);
  RenderSettings settings;
  settings.autoAlgorithm = true;
  settings.width = settings.height = 32;
  settings.timeBudgetSeconds = 6;
  PilotSamples samples;
  const RenderPlan plan = planJob(scene, &settings, {}, &samples);
  ASSERT_EQ(settings.algorithm, Algorithm::Bidirectional) << plan.why;
  ASSERT_TRUE(settings.pixelAllocation);
  EXPECT_EQ(settings.pixelAllocation->width(), 32);
  EXPECT_EQ(settings.pixelAllocation->bidirectional(), std::vector<uint8_t>(32 * 32, 1));
  const auto [lo, hi] = std::minmax_element(settings.pixelAllocation->density().begin(),
                                            settings.pixelAllocation->density().end());
  EXPECT_GT(*hi / *lo, 2.0f) << "the light and the smoke are not alike";
  EXPECT_NE(plan.why.find("s placed the samples by its error (densities "), std::string::npos)
      << plan.why;
  EXPECT_TRUE(settings.validate().empty()) << settings.validate();
  // Half of its samples, for the job's image (coordinator/job.cpp): under a seed of their own,
  // one group for each of the job's four, and their film the sum of their groups'. Here the
  // allocation is mild (densities within 10x), so they lower the error.
  EXPECT_NE(plan.why.find("half of its samples ("), std::string::npos) << plan.why;
  EXPECT_EQ(samples.seed, settings.seed ^ kAllocationSeedSalt);
  EXPECT_NE(samples.seed, settings.seed);
  ASSERT_EQ(samples.groupSums.size(), 4u);
  ASSERT_EQ(samples.groupWork.size(), 4u);
  ASSERT_EQ(samples.sums.size(), size_t(32 * 32 * 3));
  int64_t work = 0;
  for (int64_t w : samples.groupWork) work += w;
  EXPECT_EQ(samples.work, work);
  EXPECT_GT(samples.work, 0);
  double total = 0, groups = 0;
  for (double v : samples.sums) total += v;
  for (const std::vector<float>& g : samples.groupSums)
    for (double v : g) groups += v;
  EXPECT_GT(total, 0);
  EXPECT_NEAR(total, groups, 1e-5 * total);  // the groups' films are float

  RenderSettings counts;
  counts.autoAlgorithm = true;
  counts.width = counts.height = 32;
  planJob(scene, &counts, {}, &samples);
  EXPECT_EQ(counts.algorithm, Algorithm::Bidirectional);
  EXPECT_FALSE(counts.pixelAllocation);
  EXPECT_EQ(samples.work, 0) << "no pilot, no samples of one";
  RenderSettings brief = counts;
  brief.autoAlgorithm = true;
  brief.timeBudgetSeconds = 4;  // 0.4 s, under kAllocationMinSeconds
  planJob(scene, &brief);
  EXPECT_FALSE(brief.pixelAllocation);
  EXPECT_DOUBLE_EQ(allocationPilotSeconds(settings), 0.6);
}

// Pooling uniform samples with allocated ones (n_j (n_p K + n_j) / n^2): even at K = 1, a gain
// of the pilot's share, up to no gain at K = 2 + n_p / n_j, a loss above.
TEST(PlanJob, UniformSamplesJoinAnAllocatedImageOnlyWhereTheyLowerItsError) {
  EXPECT_NEAR(pooledErrorRatio(1, 9, 1.0), 0.9, 1e-12) << "uniform: a tenth more samples";
  EXPECT_NEAR(pooledErrorRatio(1, 9, 2.0 + 1.0 / 9), 1.0, 1e-12);
  EXPECT_LT(pooledErrorRatio(1, 9, 1.5), 1.0);
  EXPECT_NEAR(pooledErrorRatio(1, 9, 5.0), 1.26, 1e-12) << "light through glass";
  EXPECT_DOUBLE_EQ(pooledErrorRatio(1, 0, 5.0), 0.0) << "no job samples: the pilot's alone";
  EXPECT_DOUBLE_EQ(pooledErrorRatio(0, 0, 1.0), 1.0);
}

TEST(PlanJob, PilotSecondsAreAShareOfTheBudget) {
  RenderSettings s;
  EXPECT_DOUBLE_EQ(pilotSecondsEach(s, 4), kPilotSecondsWithoutBudget);
  s.timeBudgetSeconds = 100;
  EXPECT_DOUBLE_EQ(pilotSecondsEach(s, 4), 2.5);
  s.timeBudgetSeconds = 40;
  EXPECT_DOUBLE_EQ(pilotSecondsEach(s, 4), 1.0);
  s.timeBudgetSeconds = 30;
  EXPECT_DOUBLE_EQ(pilotSecondsEach(s, 4), 0) << "too short for a pilot";
  s.timeBudgetSeconds = 10000;
  EXPECT_DOUBLE_EQ(pilotSecondsEach(s, 4), kPilotMaxSeconds);
}

}  // namespace
}  // namespace farm
