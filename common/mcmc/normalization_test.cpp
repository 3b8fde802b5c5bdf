// Z pooled from the bootstrap's candidates and the chains' large steps: the pooling is exact
// arithmetic on the two samples' sums, and the large steps are samples of the same integrand.
#include "common/mcmc/normalization.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/render/local_render.h"
#include "common/render/render_job.h"
#include "common/sampling/rng.h"
#include "common/scene/scene.h"

namespace farm {
namespace {

// Mean and standard error as bootstrap.cpp takes them (unbiased sample variance).
void meanAndError(const std::vector<double>& x, double* mean, double* stdError) {
  double sum = 0, sumSq = 0;
  for (double v : x) {
    sum += v;
    sumSq += v * v;
  }
  const double n = double(x.size());
  *mean = sum / n;
  *stdError = std::sqrt(std::max(0.0, (sumSq - n * *mean * *mean) / (n - 1)) / n);
}

TEST(Normalization, PoolsAsOneSample) {
  Rng rng(5, 6);
  std::vector<double> candidates, all;
  LargeStepSums large;
  for (int i = 0; i < 3000; ++i) {
    const double u = rng.nextDouble();
    const double I = u < 0.01 ? 400 * u : u * u;  // heavy-tailed, as light through glass is
    if (i < 1000) {
      candidates.push_back(I);
    } else {
      ++large.count;
      large.sum += I;
      large.sumSquares += I * I;
    }
    all.push_back(I);
  }
  double bm, bse, m, se;
  meanAndError(candidates, &bm, &bse);
  meanAndError(all, &m, &se);
  const Normalization z = pooledNormalization(bm, bse, int64_t(candidates.size()), large);
  EXPECT_NEAR(z.value, m, 1e-12 * m);
  EXPECT_NEAR(z.stdError, se, 1e-9 * se);
  EXPECT_EQ(z.samples, 3000);

  const Normalization alone = pooledNormalization(bm, bse, 1000, LargeStepSums());
  EXPECT_EQ(alone.value, bm);
  EXPECT_EQ(alone.stdError, bse);
  LargeStepSums bad = large;
  bad.sum = -1;
  EXPECT_EQ(pooledNormalization(bm, bse, 1000, bad).value, bm) << "implausible sums are ignored";
}

// A large step draws every primary sample afresh, so the mean of its I is Z: the large steps'
// mean must agree with an independent bootstrap's within their joint standard error, for pssmlt
// and for mmlt (whose large steps also draw the path's length). A chain that counted the
// current path's I instead, or small steps too, would sample I in proportion to itself and
// come out high (E[I^2]/E[I]): on the Cornell box by several times the error.
TEST(Normalization, LargeStepsEstimateTheBootstrapsZ) {
  const std::string cornell = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";
  for (Algorithm a : {Algorithm::PSSMLT, Algorithm::MMLT}) {
    RenderSettings s;
    s.algorithm = a;
    s.width = 32;
    s.height = 32;
    s.mutationsPerPixel = 256;
    s.bootstrapSamples = 1 << 17;
    s.numChains = 16;
    s.seed = 21;
    auto scene = loadScene(cornell, s);
    const LocalRenderResult r = renderLocally(RenderJob(scene, s, "large steps"));
    const LargeStepSums& l = r.largeSteps;
    ASSERT_GT(l.count, 1000) << algorithmName(a);
    const double n = double(l.count), mean = l.sum / n;
    const double seLarge = std::sqrt(std::max(0.0, (l.sumSquares - n * mean * mean) / (n - 1)) / n);
    const double z = r.bootstrap.normalization, seZ = r.bootstrap.normalizationStdError;
    EXPECT_NEAR(mean, z, 4 * std::hypot(seLarge, seZ))
        << algorithmName(a) << ": large steps " << mean << " +- " << seLarge << ", bootstrap " << z
        << " +- " << seZ;
    // About the share of the mutations the large-step probability says.
    EXPECT_NEAR(n / double(r.work), s.largeStepProbability, 0.05) << algorithmName(a);
    const Normalization pooled = r.bootstrap.normalizationWith(l);
    EXPECT_LT(pooled.stdError, seZ) << algorithmName(a);
  }
}

}  // namespace
}  // namespace farm
