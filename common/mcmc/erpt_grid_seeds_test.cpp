// ERPT's seeds through density grids: their energies, summed over the paths of one camera walk,
// are an unbiased estimate of the film point's splat, the same as path tracing's (which draws
// its paths by delta tracking, independently); each strategy's share is checked too, so that a
// wrong density in either shows.
#include "common/mcmc/erpt_grid_seeds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/math/statistics.h"
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

}  // namespace
}  // namespace farm
