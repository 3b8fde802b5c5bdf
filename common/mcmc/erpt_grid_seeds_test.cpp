// ERPT's seeds through density grids: their energies, summed over the paths of one camera walk,
// are an unbiased estimate of the film point's splat, the same as path tracing's (which draws
// its paths by delta tracking, independently); each strategy's share is checked too, so that a
// wrong density in either shows. And the chains start where the pseudo-marginal target puts
// them (erpt.h's startAtSeed).
#include "common/mcmc/erpt_grid_seeds.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/math/statistics.h"
#include "common/mcmc/erpt.h"
#include "common/render/render_job.h"
#include "common/transport/path_tracer.h"

namespace farm {
namespace {

const std::string kSmokyBox = std::string(FARM_TEST_DATA_DIR) + "/smoky-box/scene.xml";

struct ChannelMeans {
  MeanEstimate channel[3];
};

ChannelMeans means(const std::vector<Spectrum>& values) {
  ChannelMeans m;
  for (int c = 0; c < 3; ++c) {
    std::vector<double> v;
    v.reserve(values.size());
    for (const Spectrum& s : values) v.push_back(double(s[c]));
    m.channel[c] = meanOfIndependent(v);
  }
  return m;
}

TEST(GridSeedSampler, SeedEnergiesSumToPathTracingsSplat) {
  RenderSettings settings;
  settings.width = settings.height = 24;
  auto scene = loadScene(kSmokyBox, settings);
  ASSERT_TRUE(hasDensityGrid(*scene));
  const int maxDepth = scene->maxDepth() == 0 ? -1 : scene->maxDepth();
  // Film points uniform over the image: the splats' means are the image's mean.
  constexpr int kWalks = 300000;
  std::vector<Spectrum> seeds(kWalks, Spectrum(0.0f)), traced(kWalks, Spectrum(0.0f));
  int byStrategy[2] = {0, 0}, inMedia = 0;
  {
    // Roulette from the first vertex, so that its factor enters every path's density.
    GridSeedSampler sampler(*scene, maxDepth, 1, 0, 1);
    Rng rng(5, 1);
    for (int i = 0; i < kWalks; ++i) {
      const Vec2f film(rng.nextFloat() * 24, rng.nextFloat() * 24);
      sampler.visit(film, rng, [&](const GridSeed& seed) {
        ASSERT_TRUE(std::isfinite(seed.energy) && seed.energy > 0);
        seeds[size_t(i)] += seed.f.color * float(seed.energy);
        ++byStrategy[seed.strategy];
        for (const PathVertex& v : seed.path->vertices) inMedia += inMedium(v);
      });
    }
  }
  {
    PathTracer tracer(*scene, maxDepth);
    Rng rng(6, 1);
    IndependentSampler sampler(&rng);
    std::vector<Splat> splats;
    for (int i = 0; i < kWalks; ++i) {
      const Vec2f film(rng.nextFloat() * 24, rng.nextFloat() * 24);
      splats.clear();
      tracer.sample(film, sampler, &splats);
      for (const Splat& s : splats) traced[size_t(i)] += s.value;
    }
  }
  // Both strategies and vertices in the grid's medium occur, or the test would not tell.
  EXPECT_GT(byStrategy[0], kWalks / 50);
  EXPECT_GT(byStrategy[1], kWalks / 5);
  EXPECT_GT(inMedia, kWalks / 10);
  const ChannelMeans a = means(seeds), b = means(traced);
  for (int c = 0; c < 3; ++c) {
    const double se = std::hypot(a.channel[c].standardError, b.channel[c].standardError);
    std::printf("channel %d: seeds %.5f +- %.5f, path tracing %.5f +- %.5f\n", c, a.channel[c].mean,
                a.channel[c].standardError, b.channel[c].mean, b.channel[c].standardError);
    EXPECT_NEAR(a.channel[c].mean, b.channel[c].mean, 4.5 * se) << "channel " << c;
    // The two draw the same paths with densities of the same shape, so their spreads are alike
    // (within 1% here): a density that is wrong by a lot shows as energies of a far larger
    // spread, which the comparison of means alone would excuse.
    EXPECT_LT(a.channel[c].standardError, 1.5 * b.channel[c].standardError) << "channel " << c;
  }
}

// Whether x passes through a density grid: the paths on which a transmittance is estimated.
bool throughGrid(const Scene& scene, const Path& x) {
  PathMedia media;
  if (!x.media(scene, &media)) return false;
  for (const PathMedia::Edge& e : media.edges) {
    for (const MediumSegment& s : e.segments) {
      if (s.medium >= 0 && s.length > 0 &&
          scene.description().media[size_t(s.medium)].type == MediumDescription::Type::Grid)
        return true;
    }
  }
  return false;
}

// A pseudo-marginal chain's target is the pair (x, u) of a path and its estimate's numbers, of
// density f^(x, u) q(u) (Kronander et al. 2015, 3.3), and ERPT's chains must start there: a seed
// of energy e = f^(x, u) w / p puts its chains at (x, u) in proportion to that. With r = f^ / f
// (f from marching 1024 steps, whose bias is far below the test's resolution), the starts'
// e min(1, 1 / r) then sums to the integral of f(x) E_q[min(r, 1)], which path tracing's paths
// estimate independently, each weighted by min(r', 1) for a fresh estimate r' of its own; on the
// paths through the grid, where r is not 1. A chain started with a fresh estimate instead sits
// at (x, u') with u' drawn from q alone, off the target, and its starts sum to the integral of
// f(x) E_q[min(1, 1 / r)] (the statistic is bounded, so that the heavy tail of 1 / r does not
// hide the difference).
TEST(GridSeedSampler, ChainsStartOnThePseudoMarginalTarget) {
  RenderSettings settings;
  settings.width = settings.height = 24;
  auto scene = loadScene(kSmokyBox, settings);
  const int maxDepth = scene->maxDepth() == 0 ? -1 : scene->maxDepth();
  constexpr int kWalks = 400000;
  std::vector<double> own(kWalks, 0.0), fresh(kWalks, 0.0), traced(kWalks, 0.0);
  int starts = 0, ownFailures = 0, freshFailures = 0, tracedThrough = 0, unevaluated = 0;
  {
    GridSeedSampler sampler(*scene, maxDepth, 1, 0);
    PathChain chain(*scene, maxDepth, MutationMix{}, 1, 0);
    Rng rng(5, 2), chainRng(5, 3);
    for (int i = 0; i < kWalks; ++i) {
      const Vec2f film(rng.nextFloat() * 24, rng.nextFloat() * 24);
      sampler.visit(film, rng, [&](const GridSeed& seed) {
        if (!throughGrid(*scene, *seed.path)) return;
        const PathContribution exact = seed.path->contribution(*scene, maxDepth);
        ASSERT_TRUE(exact.carriesLight());
        // A seed's own estimate carries light: its chain cannot fail to start.
        if (!startAtSeed(chain, *seed.path, &seed.f, chainRng)) {
          ++ownFailures;
          return;
        }
        const double logR = chain.currentContribution().logLuminance - exact.logLuminance;
        own[size_t(i)] += seed.energy * std::min(1.0, std::exp(-logR));
        ++starts;
        // The mutant, for comparison: the same seed started with a fresh estimate.
        if (startAtSeed(chain, *seed.path, nullptr, chainRng))
          fresh[size_t(i)] +=
              seed.energy * std::min(1.0, std::exp(exact.logLuminance -
                                                   chain.currentContribution().logLuminance));
        else
          ++freshFailures;
      });
    }
  }
  {
    PathTracer tracer(*scene, maxDepth);
    Rng rng(6, 2), estimateRng(6, 3);
    IndependentSampler sampler(&rng);
    const TransmittanceEstimator estimator{&estimateRng, 1, 0};
    Path x;
    for (int i = 0; i < kWalks; ++i) {
      const Vec2f film(rng.nextFloat() * 24, rng.nextFloat() * 24);
      tracer.visitPaths(film, sampler, [&](const PathTracer::TracedPath& path) {
        path.assignTo(&x);
        if (!throughGrid(*scene, x)) return;
        const PathContribution exact = x.contribution(*scene, maxDepth);
        const PathContribution estimate = x.contribution(*scene, maxDepth, &estimator);
        if (!exact.carriesLight()) {
          unevaluated += luminance(path.value) > 0;
          return;
        }
        const double r =
            estimate.carriesLight() ? std::exp(estimate.logLuminance - exact.logLuminance) : 0.0;
        traced[size_t(i)] += luminance(path.value) * std::min(r, 1.0);
        ++tracedThrough;
      });
    }
  }
  // Many paths pass through the grid, or the test would not tell.
  EXPECT_GT(starts, kWalks / 5);
  EXPECT_EQ(ownFailures, 0);
  EXPECT_GT(tracedThrough, kWalks / 20);
  EXPECT_LT(unevaluated, tracedThrough / 1000) << "paths that carry light but not by marching";
  const MeanEstimate a = meanOfIndependent(own), f = meanOfIndependent(fresh),
                     b = meanOfIndependent(traced);
  std::printf(
      "through the grid, over %d starts: seeds' own estimates %.4f +- %.4f, fresh ones %.4f +- "
      "%.4f (%d failed to start); path tracing %.4f +- %.4f (%d paths)\n",
      starts, a.mean, a.standardError, f.mean, f.standardError, freshFailures, b.mean,
      b.standardError, tracedThrough);
  std::printf("(%d paths carry light by path tracing but not by marching)\n", unevaluated);
  EXPECT_NEAR(a.mean, b.mean, 4.5 * std::hypot(a.standardError, b.standardError));
}

}  // namespace
}  // namespace farm
