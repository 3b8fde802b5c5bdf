// An ERPT tile is a work unit like the others: it flushes at seed boundaries, a tile resumed
// from a flush continues bit for bit, and a tile that is not on the film or has no deposit
// energy is refused. (Its image is checked against analytic answers and the references in
// furnace_test.cpp and reference_test.cpp.)
#include "common/mcmc/erpt.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "common/chain/resume_check.h"
#include "common/render/render_job.h"

namespace farm {
namespace {

// An ERPT job on the Cornell box at size x size, and its tiles.
std::vector<ChainSpec> erptTiles(int size, double timeBudget, int length,
                                 std::unique_ptr<RenderJob>* job) {
  RenderSettings settings;
  settings.algorithm = Algorithm::ERPT;
  settings.width = settings.height = size;
  settings.samplesPerPixel = 2;
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

}  // namespace
}  // namespace farm
