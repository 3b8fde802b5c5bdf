#pragma once
// One Kelemen-style Markov chain in primary sample space (Kelemen et al. 2002) over any
// PrimarySampleIntegrand (BDPT for pssmlt, path tracing for pssmlt-pt, the multiplexed
// strategies for mmlt), with expected-value splatting: each iteration splats the proposal with
// weight a / I(proposal) and the current state with (1 - a) / I(current), so the film holds
// sum of f / I and the image is Z / M times it (Veach 1997, eq. 11.7 with the normalization of
// the bootstrap, common/mcmc/normalization.h). With ChainSpec::largeStepMis, Kelemen's
// combination of the large steps with the chain: f / (I + b p_large) a path, the large steps'
// proposals counted once more (Kelemen et al. 2002, section 4.1).
#include <atomic>
#include <cstdint>
#include <functional>

#include "common/chain/chain_spec.h"
#include "common/mcmc/primary_sample_integrand.h"
#include "common/scene/scene.h"

namespace farm {

// I(u) of the chain's seed vector, rebuilt here: equals spec.seedContribution when this host
// computes exactly as the one that ran the bootstrap.
double seedContributionOf(const Scene& scene, const ChainSpec& spec);

// Runs the chain of spec (its algorithm names the integrand) to its budget, flushing through
// onFlush; returns at once when *cancel becomes true. Throws std::runtime_error for a corrupt
// resume state or a seed that carries no light.
void runPssmltChain(const Scene& scene, const ChainSpec& spec,
                    const std::function<bool(ChainFlush&&)>& onFlush,
                    const std::atomic<bool>* cancel = nullptr);
// The same over a given integrand (the statistical tests use low-dimensional ones).
void runPssmltChain(const Scene& scene, const PrimarySampleIntegrand& integrand,
                    const ChainSpec& spec, const std::function<bool(ChainFlush&&)>& onFlush,
                    const std::atomic<bool>* cancel = nullptr);

// The Metropolis-Hastings acceptance of a symmetric proposal, min(1, I(y) / I(x)) (Kelemen et
// al. 2002, eq. 6), for I(x) > 0.
inline double metropolisAcceptance(double proposedI, double currentI) {
  return proposedI >= currentI ? 1.0 : proposedI / currentI;
}

}  // namespace farm
