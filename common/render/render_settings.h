#pragma once
// The user's render options, shared by `farm render`, `farm submit` and the coordinator.
#include <cstdint>
#include <memory>
#include <string>

#include "common/chain/algorithm.h"
#include "common/film/pixel_allocation.h"

namespace farm {

// Which shading-normal convention the scene renders with (Scene::sidesAgree): the one its file
// gives (Mitsuba's integrator strictNormals, false when absent; strict for pbrt files), or one
// named here, which overrides it.
enum class ShadingNormals { Scene, Strict, Lax };
const char* shadingNormalsName(ShadingNormals s);  // "scene", "strict", "lax"
bool parseShadingNormals(const std::string& name, ShadingNormals* out);

// The most bootstrap candidates a job may ask for: eight bytes a candidate, all held at once,
// 2^26 is 512 MiB.
constexpr int64_t kMaxBootstrapSamples = int64_t(1) << 26;

struct RenderSettings {
  Algorithm algorithm = Algorithm::PSSMLT;
  // --algorithm auto: the coordinator picks the algorithm by the scene's plan (its first
  // candidate), then renders with it; `algorithm` is ignored until then, and holds the pick after.
  bool autoAlgorithm = false;
  // --pilot, with auto: a short pilot of each of the plan's candidates ranks them first
  // (common/render/algorithm_pilot.h). Off by default: on the corpus's tuning half it cost more
  // than it saved (docs/corpus.md, "Auto with and without its pilot").
  bool pilot = false;
  // --no-plan: render with every part the settings name, even those the scene's plan leaves out
  // (mlt's mutations for specular chains on a scene without any): what measures the saving.
  bool ignorePlan = false;
  int width = 0, height = 0;       // 0: the scene's film; one of them 0: keep the aspect ratio
  int64_t samplesPerPixel = 16;    // pt, bdpt
  int64_t mutationsPerPixel = 16;  // pssmlt
  double timeBudgetSeconds = 0;    // > 0: stop at this wall-clock budget, not at a count
  uint64_t seed = 1;
  int maxDepth = 0;  // 0: the scene's; else the longest path in edges
  ShadingNormals shadingNormals = ShadingNormals::Scene;  // --shading-normals
  // Markov chain settings (PSSMLT)
  int64_t bootstrapSamples = 0;       // candidate paths; 0: sized to the job (bootstrap_size.h)
  int numChains = 0;                  // independent chains (work units); 0: default
  float largeStepProbability = 0.3f;  // Kelemen et al. 2002, section 4
  // --combine-large-steps (pssmlt, pssmlt-pt, mmlt): each large step's proposal also counts as
  // an independent sample, weighted against the chain by multiple importance sampling (Kelemen
  // et al. 2002, section 4.1; ChainSpec::largeStepMis). Z is then the bootstrap's alone.
  bool combineLargeSteps = false;
  MutationMix mutationMix;  // mlt: how often each of Veach's mutations is proposed
  // erpt (Cline et al. 2005): seeds per pixel are samplesPerPixel; each seed starts on average
  // erptChains chains of erptLength mutations.
  double erptChains = 1;
  int erptLength = 100;
  // mlt and erpt through density grids: f's transmittances are the mean of mediumSamples
  // ratio-tracking estimates (pseudo-marginal MLT), or, with mediumMarchSteps > 0, marched with
  // that many steps per segment (deterministic, biased by the step).
  int mediumSamples = 1;
  int mediumMarchSteps = 0;
  // Mutations (or samples) a chain runs between flushes; 0: one film's worth (the pixel count,
  // within 4096 .. 2^20). Longer intervals mean fewer, denser uploads (docs/scale.md) and
  // more work lost with a worker that dies.
  int64_t flushInterval = 0;
  // > 0: the job ends once the relative MSE estimated from the spread between its chain groups
  // (common/film/batch_means.h) is at most this, or at its budget, whichever comes first.
  double untilError = 0;
  // The independent groups the chains fall into for that estimate (ChainSpec::errorGroup); 0:
  // kErrorGroups (render_job.h); 1: no estimate, and one film on the coordinator, not one a
  // group. At most the chain count (erpt: seeds per pixel).
  int errorGroups = 0;
  // pt, bdpt: where the samples land and which of the two estimators takes each cell of the film
  // (common/film/pixel_allocation.h); its film must be the job's. Empty: uniform, the
  // algorithm's estimator everywhere.
  std::shared_ptr<const PixelAllocation> pixelAllocation;

  // Empty when the settings are usable, otherwise what is wrong (for the user, one line).
  std::string validate() const;
};

}  // namespace farm
