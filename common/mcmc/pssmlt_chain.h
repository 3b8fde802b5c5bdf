#pragma once
// One Kelemen-style Markov chain over BDPT in primary sample space (Kelemen et al. 2002), with
// expected-value splatting: each iteration splats the proposal with weight a / I(proposal) and
// the current state with (1 - a) / I(current), so the film holds sum of f / I and the image is
// Z / M times it (Veach 1997, eq. 11.7 with the normalization of ../shared/DESIGN.md).
#include <atomic>
#include <cstdint>
#include <functional>

#include "common/render/chain_spec.h"
#include "common/render/render_job.h"
#include "common/scene/scene.h"

namespace farm {

// I(u) of the chain's seed vector, rebuilt here: equals spec.seedContribution when this host
// computes exactly as the one that ran the bootstrap.
double seedContributionOf(const Scene& scene, const ChainSpec& spec);

void runPssmltChain(const Scene& scene, const ChainSpec& spec,
                    const std::function<bool(ChainFlush&&)>& onFlush,
                    const std::atomic<bool>* cancel = nullptr);

}  // namespace farm
