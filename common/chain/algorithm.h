#pragma once
// The rendering algorithms a job can ask for, and the parameters that choose among the
// mutations of path-space MLT: what a ChainSpec carries to a worker and RenderSettings to the
// coordinator.
#include <string>
#include <vector>

namespace farm {

enum class Algorithm {
  PathTracing,    // "pt": path tracing with next-event estimation and MIS
  Bidirectional,  // "bdpt": bidirectional path tracing, every (s, t) strategy, MIS
  PSSMLT,         // "pssmlt": primary-sample-space MLT over BDPT (Kelemen et al. 2002)
  PSSMLTOverPT,   // "pssmlt-pt": the same over path tracing
  MMLT,           // "mmlt": multiplexed MLT (Hachisuka et al. 2014)
  MLT,            // "mlt": path-space MLT with Veach's mutations (Veach and Guibas 1997)
  ERPT,           // "erpt": energy redistribution path tracing (Cline et al. 2005)
};

const char* algorithmName(Algorithm a);
bool parseAlgorithm(const std::string& name, Algorithm* out);  // accepts algorithmName()s
// "pt, bdpt, ..." for messages and --help.
const char* algorithmList();
// Every algorithm this build runs (what a worker offers).
std::vector<Algorithm> allAlgorithms();

// Chains started from bootstrap seeds whose image is Z / mutations * (sum of splats).
inline bool isMarkovChain(Algorithm a) {
  return a == Algorithm::PSSMLT || a == Algorithm::PSSMLTOverPT || a == Algorithm::MMLT ||
         a == Algorithm::MLT;
}
// Algorithms whose coordinator estimates Z first: the Markov chains, and ERPT, whose deposit
// energy is a share of it.
inline bool needsBootstrap(Algorithm a) {
  return isMarkovChain(a) || a == Algorithm::ERPT;
}
// Chains whose state is a primary-sample vector (Kelemen et al. 2002).
inline bool isPrimarySampleSpace(Algorithm a) {
  return a == Algorithm::PSSMLT || a == Algorithm::PSSMLTOverPT || a == Algorithm::MMLT;
}

// How often path-space MLT proposes each of Veach's mutations. Weights, not probabilities: at
// each step they are normalized over the mutations that apply to the current path (Veach 1997,
// 11.4). The bidirectional mutation applies to every path and keeps the chain ergodic, so its
// weight must be positive.
struct MutationMix {
  double bidirectional = 0.4;
  double lensSubpath = 0.1;
  double lensPerturbation = 0.2;
  double causticPerturbation = 0.15;
  double multiChainPerturbation = 0.15;
  // Applies only to paths whose first non-specular vertex from the camera is lit through a
  // specular chain (L S+ D S* E): on the water caustic it is what moves the chains that the
  // bootstrap seeds there (manifold_perturbation.h).
  double manifoldPerturbation = 0.2;

  bool operator==(const MutationMix& o) const;
};

// "bidir=0.4,lens-subpath=0.1,lens=0.2,caustic=0.15,multichain=0.15,manifold=0.2"; names left out
// keep their defaults. False with *error naming the problem.
bool parseMutationMix(const std::string& text, MutationMix* out, std::string* error);
std::string formatMutationMix(const MutationMix& mix);
// Empty when usable: finite, non-negative, bidirectional > 0.
std::string validateMutationMix(const MutationMix& mix);

}  // namespace farm
