#pragma once
// Energy redistribution path tracing (Cline, Talbot and Egbert 2005). Path tracing draws seeds,
// stratified over the pixels of a tile; each path a seed builds, carrying energy e (the
// luminance of its splat), starts on average e / (N e_d) chains of N mutations that each deposit
// e_d (the path's colour of luminance e_d), so that its energy is spread over nearby paths in
// the proportions of f instead of landing on one pixel. The mutations are Veach's lens and
// caustic perturbations and the manifold perturbation (for paths lit through a specular chain),
// which keep f stationary; the number of chains is e / (N e_d) rounded up
// or down at random, so the expected deposit of every seed path is its energy and the image is
// unbiased, whatever e_d is. e_d = Z / (chains per seed * N), Z the mean energy of a seed (from
// the bootstrap), so that a seed starts about `chains per seed` chains. Through density grids
// the seeds come from GridSeedSampler instead (erpt_grid_seeds.h), and the chains start with
// each seed's own estimate of f, as pseudo-marginal chains must.
//
// A work unit is a tile with its seeds (pass after pass over its pixels, seed k of pixel p
// drawing from the stream (seed, p, pass)); it flushes and resumes at seed boundaries. Under a
// time budget the units stop unevenly, so there each seed lands anywhere on the film instead (as
// path tracing's samples do then). A seed path of extreme energy starts at most kMaxErptChains
// chains, each depositing its share.
#include <atomic>
#include <functional>

#include "common/chain/chain_spec.h"
#include "common/mcmc/mlt_chain.h"
#include "common/scene/scene.h"

namespace farm {

constexpr int kMaxErptChains = 64;

// Starts `chain` at a seed path x: at (x, *fx) where the seed carries its own estimate fx of
// f(x) (through density grids, erpt_grid_seeds.h), the pair a pseudo-marginal chain must start
// from, since seeds land on x in proportion to that estimate; with a fresh evaluation of f(x)
// otherwise. False when x carries no light.
bool startAtSeed(PathChain& chain, const Path& x, const PathContribution* fx, Rng& rng);

void runErptTile(const Scene& scene, const ChainSpec& spec,
                 const std::function<bool(ChainFlush&&)>& onFlush,
                 const std::atomic<bool>* cancel = nullptr);

}  // namespace farm
