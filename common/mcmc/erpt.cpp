#include "common/mcmc/erpt.h"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "common/chain/chain_flusher.h"
#include "common/mcmc/erpt_grid_seeds.h"
#include "common/mcmc/mlt_chain.h"
#include "common/transport/path_tracer.h"

namespace farm {

namespace {
constexpr uint64_t kErptDomain = 0xe497;
}  // namespace

bool startAtSeed(PathChain& chain, const Path& x, const PathContribution* fx, Rng& rng) {
  if (!fx) return chain.start(x, rng);
  chain.resume(x, *fx);
  return true;
}

void runErptTile(const Scene& scene, const ChainSpec& spec,
                 const std::function<bool(ChainFlush&&)>& onFlush,
                 const std::atomic<bool>* cancel) {
  const int64_t tilePixels = int64_t(spec.tileWidth) * spec.tileHeight;
  if (tilePixels <= 0 || spec.tileX < 0 || spec.tileY < 0 ||
      spec.tileX + spec.tileWidth > scene.camera().width() ||
      spec.tileY + spec.tileHeight > scene.camera().height())
    throw std::runtime_error("chain " + std::to_string(spec.chainIndex) +
                             ": the tile is not on the film");
  if (!(spec.erptDeposit > 0) || spec.erptLength < 1 || !(spec.erptChains > 0))
    throw std::runtime_error("chain " + std::to_string(spec.chainIndex) +
                             ": ERPT needs a positive deposit, length and chain count");
  if (spec.firstSample < 0 || spec.firstSample % tilePixels != 0)
    throw std::runtime_error("chain " + std::to_string(spec.chainIndex) +
                             ": its first seed must start a pass over the tile");
  // Cline et al.'s lens and caustic perturbations, and the manifold perturbation at mlt's
  // default weight, which moves the seeds of paths lit through a specular chain (L S+ D S* E)
  // that the other two cannot (manifold_perturbation.h).
  MutationMix perturbations{0, 0, 1, 1, 0, 0.2};
  PathChain chain(scene, spec.maxDepth, perturbations, spec.mediumSamples, spec.mediumMarchSteps);
  PathTracer tracer(scene, spec.maxDepth);
  std::unique_ptr<GridSeedSampler> gridSeeds;
  if (hasDensityGrid(scene)) {
    gridSeeds = std::make_unique<GridSeedSampler>(scene, spec.maxDepth, spec.mediumSamples,
                                                  spec.mediumMarchSteps);
  }
  ChainFlusher flusher(spec, scene, onFlush, cancel);
  SplatBuffer& film = flusher.film();
  const double length = spec.erptLength;
  const int width = scene.camera().width();
  Path x;
  while (flusher.budgetLeft()) {
    // Seeds are numbered within the tile: a work unit of later passes starts at firstSample.
    const int64_t k = (spec.budget >= 0 ? spec.firstSample : 0) + flusher.done();
    Vec2f seedFilm;
    Rng rng;
    if (spec.budget >= 0) {
      // A seed budget: pass after pass over the tile's pixels, one stratified seed each.
      const int64_t local = k % tilePixels, pass = k / tilePixels;
      const int px = spec.tileX + int(local % spec.tileWidth);
      const int py = spec.tileY + int(local / spec.tileWidth);
      rng = Rng(spec.seed, streamId(kErptDomain, streamId(uint64_t(py) * width + px, pass)));
      seedFilm = Vec2f(std::min(px + rng.nextFloat(), std::nextafter(float(px + 1), 0.0f)),
                       std::min(py + rng.nextFloat(), std::nextafter(float(py + 1), 0.0f)));
    } else {
      // A time budget stops the units wherever they are, some further than others: each seed
      // then lands anywhere on the film, so that the image is unbiased at any count.
      rng = Rng(spec.seed, streamId(kErptDomain, streamId(spec.chainIndex, uint64_t(k))));
      const Camera& camera = scene.camera();
      seedFilm = Vec2f(
          std::min(rng.nextFloat() * camera.width(), std::nextafter(float(camera.width()), 0.0f)),
          std::min(rng.nextFloat() * camera.height(),
                   std::nextafter(float(camera.height()), 0.0f)));
    }
    // A seed path x whose chains start at (x, fx): fx the chain's own estimate of f(x) through
    // grids (erpt_grid_seeds.h), or f(x) itself, which start() evaluates, elsewhere.
    auto redistribute = [&](const Path& x, const PathContribution* fx, const Vec2f& at,
                            const Spectrum& value) {
      if (!flusher.check(value)) return;
      const double energy = luminance(value);
      if (!(energy > 0)) return;
      auto start = [&] { return startAtSeed(chain, x, fx, rng); };
      if (!start()) {
        // A path the chains cannot evaluate (a lobe at the edge of rounding): its energy
        // stays where path tracing put it.
        film.add(at, value);
        return;
      }
      const double expectedChains = energy / (length * spec.erptDeposit);
      int chains;
      double deposit;
      if (expectedChains <= kMaxErptChains) {
        chains = int(std::floor(rng.nextDouble() + expectedChains));
        deposit = spec.erptDeposit;
      } else {
        chains = kMaxErptChains;
        deposit = energy / (length * kMaxErptChains);
      }
      for (int c = 0; c < chains; ++c) {
        if (c > 0) start();  // the first starts where the check above left it
        for (int i = 0; i < spec.erptLength; ++i) chain.step(rng, film, float(deposit), &flusher);
      }
    };
    if (gridSeeds) {
      gridSeeds->visit(seedFilm, rng, [&](const GridSeed& seed) {
        redistribute(*seed.path, &seed.f, seed.f.film, seed.f.color * float(seed.energy));
      });
    } else {
      IndependentSampler sampler(&rng);
      tracer.visitPaths(seedFilm, sampler, [&](const PathTracer::TracedPath& seed) {
        seed.assignTo(&x);
        redistribute(x, nullptr, seedFilm, seed.value);
      });
    }
    const int64_t doneAfter = k + 1;
    if (!flusher.countMutation(tracer.rays() + chain.rays() + (gridSeeds ? gridSeeds->rays() : 0),
                               [&] { return std::to_string(doneAfter); }))
      return;
  }
}

}  // namespace farm
