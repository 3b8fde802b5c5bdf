// Seed resampling: every pick carries light, and picks follow the weights (systematic
// resampling gives each candidate floor or ceil of n w_i / W picks). A candidate's splats carry
// its I. The connections given up are counted for the candidates Z is made of.
#include "common/mcmc/bootstrap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "common/mcmc/bootstrap_size.h"
#include "common/render/render_job.h"
#include "common/sampling/rng.h"
#include "common/scene/test_scenes.h"

namespace farm {
namespace {

// Rounding in the running sums can carry the last targets past the last candidate with weight;
// trailing zero-weight candidates must still never be picked (a chain seeded there has nothing
// to start from).
TEST(ResampleSeeds, NeverPicksACandidateWithoutWeight) {
  // Weights of a few subnormal units: the step W / n rounds to a whole unit, so the running
  // targets overshoot the total by up to half a step.
  const double unit = std::numeric_limits<double>::denorm_min();
  for (uint64_t seed = 0; seed < 64; ++seed) {
    for (int n = 2; n <= 5; ++n) {
      const std::vector<double> tiny = {unit, 2 * unit, 0.0, 0.0};
      for (int64_t p : resampleSeeds(tiny, n, seed))
        ASSERT_GT(tiny[size_t(p)], 0) << "seed " << seed << ", n " << n << " picked " << p;
    }
  }
  Rng rng(7, 7);
  for (int trial = 0; trial < 2000; ++trial) {
    const int count = 1 + int(rng.nextUint() % 64);
    std::vector<double> w(size_t(count) + 1 + rng.nextUint() % 8, 0.0);
    for (int i = 0; i < count; ++i) {
      // weights spanning many magnitudes, some zero, so that the sums round
      w[size_t(i)] =
          rng.nextFloat() < 0.2f ? 0.0 : std::ldexp(rng.nextDouble(), -int(rng.nextUint() % 40));
    }
    w[size_t(count) - 1] = 0.1 + 0.3 * rng.nextDouble();  // at least one carries light
    const int n = 1 + int(rng.nextUint() % 300);
    std::vector<int64_t> picks = resampleSeeds(w, n, uint64_t(trial));
    ASSERT_EQ(picks.size(), size_t(n));
    for (int64_t p : picks) {
      ASSERT_GE(p, 0);
      ASSERT_LT(p, int64_t(w.size()));
      ASSERT_GT(w[size_t(p)], 0) << "trial " << trial << " picked " << p << " of " << w.size();
    }
  }
}

TEST(ResampleSeeds, PicksFollowTheWeights) {
  const std::vector<double> w = {0.0, 3.0, 1.0, 0.0, 4.0, 0.0};
  const int n = 800;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    std::vector<int64_t> picks = resampleSeeds(w, n, seed);
    std::vector<int> counts(w.size(), 0);
    for (int64_t p : picks) ++counts[size_t(p)];
    for (size_t i = 0; i < w.size(); ++i) {
      double expected = n * w[i] / 8.0;
      EXPECT_GE(counts[i], std::floor(expected)) << i;
      EXPECT_LE(counts[i], std::ceil(expected)) << i;
    }
  }
  EXPECT_TRUE(resampleSeeds({0.0, 0.0}, 4, 1).empty());
  EXPECT_TRUE(resampleSeeds({}, 4, 1).empty());
}

// Each candidate's splats (the glass ball: BDPT's paths and manifold next-event estimation's)
// land on the film and their luminance adds up to its I, so that their average is an image
// whose total is Z: the image the water caustic's reference test holds mlt's chains to.
TEST(CandidateSplats, AddUpToEachCandidatesContribution) {
  RenderSettings settings;
  settings.width = settings.height = 24;
  auto scene = loadScene(glassBallScene(), settings);
  const int maxDepth = 8;
  int carrying = 0;
  for (int64_t i = 0; i < 2048; ++i) {
    double sum = 0;
    visitCandidateSplats(*scene, maxDepth, 5, i, [&](const Splat& s) {
      EXPECT_TRUE(s.film.x >= 0 && s.film.x < 24 && s.film.y >= 0 && s.film.y < 24)
          << s.film.x << ", " << s.film.y;
      sum += luminance(s.value);
    });
    const double I = evaluateCandidate(*scene, Algorithm::MLT, maxDepth, 5, i);
    EXPECT_NEAR(sum, I, 1e-5 * I) << "candidate " << i;
    if (I > 0) ++carrying;
  }
  EXPECT_GT(carrying, 1000);
}

// Each candidate's connections given up (manifold next-event estimation's, left out of its I)
// are summed over the candidates Z is made of: a count from index 0, or those after a pilot,
// whose own are not Z's. Here the first 1000 stream indices give up one each, and every seventh
// after them two.
TEST(ExtendCandidates, CountsTheConnectionsGivenUpForZsCandidates) {
  const CandidateEvaluator evaluate = [](int64_t index) {
    return CandidateValue(1.0 + double(index % 3), index < 1000 ? 1 : index % 7 == 0 ? 2 : 0);
  };
  const auto expected = [](int64_t first, int64_t count) {
    int64_t n = 0;
    for (int64_t i = first; i < first + count; ++i) n += i < 1000 ? 1 : i % 7 == 0 ? 2 : 0;
    return n;
  };
  BootstrapCandidates c;
  ASSERT_TRUE(extendCandidates(evaluate, 10000, &c));
  EXPECT_EQ(c.abandoned, expected(0, 10000));
  ASSERT_TRUE(extendCandidates(evaluate, 30000, &c));  // extended: the new ones added
  EXPECT_EQ(c.abandoned, expected(0, 30000));

  BootstrapRequest request;
  request.algorithm = Algorithm::PSSMLT;
  request.pixels = 1 << 12;
  request.plannedWork = 1 << 16;
  SizedCandidates sized;
  ASSERT_TRUE(drawSizedCandidates(evaluate, request, &sized));
  ASSERT_GE(sized.pilot, 1000);  // the first 1000 are the pilot's
  const int64_t count = int64_t(sized.candidates.contributions.size());
  EXPECT_EQ(sized.candidates.abandoned, expected(sized.pilot, count));
  EXPECT_GE(expected(0, count), expected(sized.pilot, count) + 500);  // so the two differ
}

}  // namespace
}  // namespace farm
