#pragma once
// The render a scene implies (docs/design.md, "Leave out what a scene does not need"): which
// algorithm, which of path-space MLT's mutations with which weights, and each path-space part
// either in or left out, with the reason. `farm plan SCENE` prints it; every job carries it in
// its report. A part left out is gone from the code path: mlt's mutations by a zero weight, which
// PathChain::select skips before asking whether the mutation applies; the others by the scene's
// own data, which the code they name tests first (Camera::hasLens, Scene::bsdfAt's texture
// index, Lights::environment, Scene::hasMedia, ManifoldNextEvent::active).
//
// With --algorithm auto the plan also names the candidates a short pilot ranks
// (common/render/algorithm_pilot.h). The pilot's yardstick, the reference-free error estimate,
// sees noise but not bias, so the analysis decides which algorithms may compete at all: where
// light arrives along specular-diffuse-specular paths that only manifold walks connect, the
// others' pilots would look good by missing that light, and path-space MLT is the only
// candidate.
#include <string>
#include <vector>

#include "common/chain/algorithm.h"
#include "common/plan/scene_analysis.h"

namespace farm {

struct PlanPart {
  std::string name;  // "caustic perturbation", "lens sampling", ...
  bool enabled = true;
  std::string reason;
};

// One candidate's pilot: its render seconds (after its bootstrap), the relative MSE its chain
// groups' spread estimated and, where three or more candidates rendered, the one their images'
// differences estimate (common/film/cross_estimate.h); score = the larger relMSE x seconds, the
// error one second of it would leave (relative MSE falls as 1 / time), lower is better.
struct PilotFigure {
  Algorithm algorithm = Algorithm::PathTracing;
  double seconds = 0;
  double bootstrapSeconds = 0;
  double estimatedRelMse = -1;  // < 0: none (failure says why)
  double crossRelMse = -1;      // < 0: fewer than three candidates rendered
  double score = -1;
  std::string failure;
};

struct RenderPlan {
  SceneAnalysis scene;
  Algorithm algorithm = Algorithm::PSSMLT;  // what the job renders with
  bool automatic = false;                   // chosen by the plan (--algorithm auto)
  bool applied = true;                      // false: --no-plan, every part the settings name
  // --algorithm auto: the candidates the pilot ranks, and why the others are not among them.
  std::vector<Algorithm> shortlist;
  std::vector<std::string> notShortlisted;
  std::string why;          // why this algorithm, or this shortlist
  MutationMix mutationMix;  // mlt's, with the parts left out at zero weight
  // The chain count: requested (--chains, > 0), or the plan's where it departs from the
  // default (kSdsChains for the Markov chains under any specular-diffuse-specular light), or 0:
  // the default.
  int requestedChains = 0;
  int chains = 0;
  std::string chainsReason;
  std::vector<PlanPart> parts;
  std::vector<PilotFigure> pilot;  // filled by the pilot, best score first

  // Sets the algorithm and the parts that follow from it (the mutations are mlt's).
  void choose(Algorithm chosen);
  // What `farm plan` prints and every report carries, a line each, no newlines.
  std::vector<std::string> describe() const;
};

// The Markov chains' count (pssmlt, pssmlt-pt, mmlt, mlt) where any light arrives along
// specular-diffuse-specular paths (SceneAnalysis::someSpecularDiffuseSpecular), in place of
// the default 64: such a chain seldom leaves the caustic it starts on, and a chain that found a
// bright one keeps its share of the image there for thousands of mutations, so more and
// shorter chains spread that share. Measured with mlt on water-caustic (lax normals, 30 s,
// seeds 1-3; relative MSE against the reference): 7.4, 0.79, 1.6 with 64 chains; 0.89, 1.4,
// 0.87 with 256; 0.38, 0.70, 1.3 with 1024. With mmlt on veach-bidir (30 s, seeds 1-4): 0.0053,
// 0.47, 0.0062, 0.0055 with 64; 0.0052, 0.46, 0.0065, 0.012 with 256; 0.0052, 0.015, 0.0050,
// 0.0050 with 1024 (docs/plan.md).
constexpr int kSdsChains = 1024;

// Below this share of the surfaces the camera sees that see a light sample
// (SceneAnalysis::directlyLit), the lights count as hidden and bdpt, not pt, renders a scene
// without specular surfaces first. On the corpus's tuning half (tools/make_corpus.py) the
// boxed-in light's room measured 20%, the open rooms 53-79%.
constexpr double kFewDirectlyLit = 0.35;

// At least this share of light rays meeting a specular surface first
// (SceneAnalysis::specularLit), with some specular-diffuse-specular light, counts as lights
// inside glass: every path leaves the light through the specular shell, so bdpt's light
// subpaths carry it out and connect to the camera's, and bdpt renders first. The corpus's
// lights in glass measure 100%, veach-bidir (a lamp beside a glass egg, where bdpt's fireflies
// from the egg's caustic left 4.7x mmlt's mean relative MSE at 10 s) 0.7%.
constexpr double kLightsInGlass = 0.9;

// At least this share of the light along camera rays taken by media before the first surface
// (SceneAnalysis::mediaSeen) is fog before the camera: there the specular-diffuse-specular
// rules, fitted in vacuum (water-caustic, veach-bidir), do not pick the candidates, and a scene
// with specular surfaces renders as one without such light. Fog scatters light towards the
// camera from every depth, and pt and bdpt connect each scattering vertex to the lights; what
// only a chain finds through the glass is a share of the image the fog has dimmed. On the
// corpus's tuning half the fog around a glass ball under a small light (fog-0: the fog takes
// 14% of the light along camera rays) left mmlt 2.0-2.3x the best's error and mlt 8-17x, where pt,
// bdpt and pssmlt led, a few tens of percent apart (docs/corpus.md). A medium too thin to matter
// (an extinction of 1e-6 over the room) takes about nothing and leaves the rules as in vacuum.
constexpr double kFoggy = 0.05;

// The plan for rendering with `requested` (ignored when automatic: the analysis picks the
// shortlist and, until a pilot ranks it, its first entry), mlt's `requestedMix` and
// `requestedChains` (0: the plan's).
RenderPlan planRender(const SceneAnalysis& scene, Algorithm requested, bool automatic,
                      const MutationMix& requestedMix, int requestedChains = 0);

// The mix with the mutations a scene without specular surfaces never uses at zero weight: the
// multi-chain perturbation and the manifold walks move specular chains (Veach 1997, 11.4.4;
// Jakob and Marschner 2012), which no path of such a scene has, and at zero weight
// PathChain::select does not even ask whether they apply: the chain, and the image, are the
// same, less the asking. The caustic perturbation stays (render_plan.cpp says why).
// Unchanged for scenes with specular surfaces.
MutationMix plannedMutationMix(const SceneAnalysis& scene, const MutationMix& requested);

}  // namespace farm
