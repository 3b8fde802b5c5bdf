// An ERPT tile is a work unit like the others: it flushes at seed boundaries, a tile resumed
// from a flush continues bit for bit, and a tile that is not on the film or has no deposit
// energy is refused. (Its image is checked against analytic answers and the references in
// furnace_test.cpp and reference_test.cpp.)
#include "common/mcmc/erpt.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "common/chain/resume_check.h"
#include "common/render/render_job.h"

namespace farm {
namespace {

// An ERPT job on the Cornell box at size x size, and its tiles (one work unit a tile with one
// error group; a unit a tile and group otherwise).
std::vector<ChainSpec> erptTiles(int size, double timeBudget, int length,
                                 std::unique_ptr<RenderJob>* job, int spp = 2, int groups = 1) {
  RenderSettings settings;
  settings.algorithm = Algorithm::ERPT;
  settings.width = settings.height = size;
  settings.samplesPerPixel = spp;
  settings.errorGroups = groups;
  settings.timeBudgetSeconds = timeBudget;
  settings.erptLength = length;
  settings.bootstrapSamples = 1 << 14;
  auto scene = loadScene(std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml", settings);
  *job = std::make_unique<RenderJob>(scene, settings, "erpt");
  return (*job)->planChains((*job)->bootstrap());
}

TEST(Erpt, ResumedTileContinuesExactly) {
  std::unique_ptr<RenderJob> owner;
  std::vector<ChainSpec> tiles = erptTiles(48, 0, 30, &owner);
  const RenderJob& job = *owner;
  ASSERT_EQ(tiles.size(), 4u);  // 32 x 32, 16 x 32, 32 x 16, 16 x 16
  EXPECT_EQ(tiles[3].tileWidth, 16);
  EXPECT_EQ(tiles[3].tileHeight, 16);
  ChainSpec spec = tiles[0];
  spec.flushInterval = 512;
  std::vector<ChainFlush> whole = expectResumesExactly(
      spec, 1, [&](const ChainSpec& c, const FlushSink& sink) { job.runChain(c, sink); });
  ASSERT_EQ(whole.size(), 4u);  // 2048 seeds
  EXPECT_TRUE(whole.back().finished);
  double energy = 0;
  for (const ChainFlush& f : whole) {
    for (float v : f.splats) energy += v;
  }
  EXPECT_GT(energy, 0);

  ChainSpec offFilm = spec;
  offFilm.tileX = 40;
  EXPECT_THROW(job.runChain(offFilm, [](ChainFlush&&) { return true; }), std::runtime_error);
  ChainSpec noDeposit = spec;
  noDeposit.erptDeposit = 0;
  EXPECT_THROW(job.runChain(noDeposit, [](ChainFlush&&) { return true; }), std::runtime_error);
}

// Under a time budget a unit may stop anywhere, so its seeds must not favour its own tile: a
// few hundred seeds of the first tile deposit energy in every quadrant of the film.
TEST(Erpt, TimeBudgetedSeedsCoverTheFilm) {
  std::unique_ptr<RenderJob> owner;
  std::vector<ChainSpec> tiles = erptTiles(64, 10, 5, &owner);
  const RenderJob& job = *owner;
  ASSERT_EQ(tiles.size(), 4u);
  ChainSpec spec = tiles[0];
  EXPECT_LT(spec.budget, 0);
  spec.flushInterval = 400;  // and stop it at its first flush
  double quadrant[4] = {0, 0, 0, 0};
  job.runChain(spec, [&](ChainFlush&& f) {
    for (int y = 0; y < f.height; ++y) {
      for (int x = 0; x < f.width; ++x)
        quadrant[(x * 2 / f.width) + 2 * (y * 2 / f.height)] +=
            f.splats[size_t(y * f.width + x) * 3 + 1];
    }
    return false;
  });
  for (double q : quadrant) EXPECT_GT(q, 0);
}

// With error groups, each tile's passes are split among the groups, whole passes each, group
// after group: the units of a tile run the undivided tile's seeds, so their flushes sum to its
// film (to float rounding), and each group covers every tile.
TEST(Erpt, ErrorGroupsSplitEachTilesPassesAndKeepItsSeeds) {
  std::unique_ptr<RenderJob> wholeOwner, splitOwner;
  const std::vector<ChainSpec> whole = erptTiles(48, 0, 10, &wholeOwner, 5, 1);
  const std::vector<ChainSpec> split = erptTiles(48, 0, 10, &splitOwner, 5, 2);
  ASSERT_EQ(whole.size(), 4u);
  ASSERT_EQ(split.size(), 8u);
  const int64_t tilePixels = 32 * 32;
  for (size_t t = 0; t < 4; ++t) {
    EXPECT_EQ(split[t].errorGroup, 0u);
    EXPECT_EQ(split[4 + t].errorGroup, 1u);
    EXPECT_EQ(split[t].tileX, whole[t].tileX);
    EXPECT_EQ(split[4 + t].tileY, whole[t].tileY);
  }
  EXPECT_EQ(split[0].firstSample, 0);
  EXPECT_EQ(split[0].budget, 3 * tilePixels);  // 5 passes: 3 and 2
  EXPECT_EQ(split[4].firstSample, 3 * tilePixels);
  EXPECT_EQ(split[4].budget, 2 * tilePixels);

  auto film = [](const RenderJob& job, ChainSpec spec) {
    std::vector<double> sum;
    spec.flushInterval = spec.budget;
    job.runChain(spec, [&](ChainFlush&& f) {
      sum.resize(f.splats.size(), 0.0);
      for (size_t i = 0; i < f.splats.size(); ++i) sum[i] += f.splats[i];
      return true;
    });
    return sum;
  };
  const std::vector<double> expected = film(*wholeOwner, whole[0]);
  std::vector<double> sum = film(*splitOwner, split[0]);
  const std::vector<double> second = film(*splitOwner, split[4]);
  ASSERT_EQ(sum.size(), expected.size());
  double total = 0, worst = 0;
  for (size_t i = 0; i < sum.size(); ++i) {
    total += expected[i];
    worst = std::max(worst, std::abs(sum[i] + second[i] - expected[i]) / (1 + expected[i]));
  }
  EXPECT_GT(total, 0);
  EXPECT_LT(worst, 1e-4);

  ChainSpec offPass = split[4];
  offPass.firstSample += 1;
  EXPECT_THROW(splitOwner->runChain(offPass, [](ChainFlush&&) { return true; }),
               std::runtime_error);
}

}  // namespace
}  // namespace farm
