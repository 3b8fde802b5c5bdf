#include "common/plan/render_plan.h"

#include <algorithm>
#include <cstdio>

namespace farm {

namespace {

bool usable(const SceneAnalysis& s, Algorithm a) {
  return std::find(s.usable.begin(), s.usable.end(), a) != s.usable.end();
}

std::string percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f%%", 100 * x);
  return buf;
}

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", x);
  return buf;
}

// Fog before the camera (kFoggy): the probes see glass through a medium's boundary, but the
// specular-diffuse-specular rules (the candidates, the chains' count) were fitted in vacuum
// (render_plan.h says why they do not hold there).
bool foggy(const SceneAnalysis& s) {
  return s.mediaSeen >= kFoggy;
}
bool someSdsRule(const SceneAnalysis& s) {
  return s.someSpecularDiffuseSpecular() && !foggy(s);
}

// The pilot's candidates and why the others are not among them.
void shortlist(const SceneAnalysis& s, RenderPlan* plan) {
  for (const auto& [a, why] : s.refused)
    plan->notShortlisted.push_back(std::string(algorithmName(a)) + ": " + why);
  if (s.specularDiffuseSpecular() && !foggy(s) && usable(s, Algorithm::MLT)) {
    plan->shortlist = {Algorithm::MLT};
    plan->why =
        "light reaches the camera along specular-diffuse-specular paths (" +
        percent(s.specularSeen) + " of camera rays and " + percent(s.specularLit) +
        " of light rays first meet a specular surface, and every light is small): only "
        "path-space MLT's manifold walks connect them; the others would miss that light, and a "
        "pilot, which sees noise and not missing light, cannot rank them";
    for (Algorithm a : s.usable) {
      if (a != Algorithm::MLT)
        plan->notShortlisted.push_back(std::string(algorithmName(a)) +
                                       ": misses the specular-diffuse-specular light");
    }
    return;
  }
  // Some such light, but little: pt and bdpt reach it only by hitting a small light, rare and
  // very bright samples (fireflies) that a pilot of seconds does not see. Measured on
  // veach-bidir (1% of camera rays and 0.7% of light rays meet its glass first): bdpt's
  // relative MSE went from 0.004 to 0.087 in one second at 29 s, and ended at 0.041 at 100 s,
  // pt's at 0.034; the Markov chains spread such paths: mmlt 0.0022, mlt 0.0065, pssmlt 0.015.
  const bool someSds = someSdsRule(s);
  // Otherwise three candidates, the first being what renders (with --pilot, unless the pilot
  // finds another clearly better). Fitted on the corpus's tuning half (tools/make_corpus.py;
  // docs/corpus.md) and the shared scenes: where the lights are in sight of most of what the camera
  // sees, pt and bdpt lead, a few tens of percent apart either way, and the Markov chains leave
  // 3-35x their error (mlt 12x on glass and metal objects, 19-35x under an environment). pt first
  // without specular surfaces (within 1.2x of bdpt on every such tuning scene; bdpt first under
  // small lights, as before, left 1.6x under a tiny one; veach-mis, whose glossy plates favour
  // bdpt, pays 1.14-1.27x); with them, pt first in a room, bdpt first under an environment or
  // in fog (below). Where the lights are hidden from most of it (SceneAnalysis::directlyLit),
  // next-event estimation mostly meets the occluder: bdpt first without specular surfaces (the
  // boxed-in light: pt 11x bdpt's error) and mlt first with them (veach-ajar's door: mlt led at
  // 10, 30 and 100 s, 0.011 at 100 s against bdpt's 0.023).
  const bool hidden = s.directlyLit < kFewDirectlyLit;
  std::vector<Algorithm> wanted;
  std::string why;
  const std::string lit =
      "the lights in sight of " + percent(s.directlyLit) + " of what the camera sees first";
  // Lights inside glass (kLightsInGlass): all the light leaves through the specular shell, and
  // bdpt's light subpaths follow it out, then connect (t >= 2) to diffuse points the camera
  // sees; only the few camera paths through the glass onto a caustic are left to chance.
  // Fitted on the tuning half's two such scenes (seeds 1-3, docs/corpus.md): bdpt led in three
  // cells of four, pssmlt 1.8-3.2x its error there, mmlt 3-1400x (a chain held on one bright
  // path at seed 3).
  const bool lightsInGlass = someSds && s.specularLit >= kLightsInGlass;
  if (lightsInGlass) {
    wanted = {Algorithm::Bidirectional, Algorithm::PSSMLT, Algorithm::MMLT};
    why = "the lights inside glass (" + percent(s.specularLit) +
          " of light rays meet a specular surface first, every light small): bdpt's light "
          "subpaths carry the light out through it, so bdpt first";
  } else if (someSds) {
    wanted = {Algorithm::MMLT, Algorithm::PSSMLT, Algorithm::MLT};
    why = "some light comes along specular-diffuse-specular paths (" + percent(s.specularSeen) +
          " of camera rays and " + percent(s.specularLit) +
          " of light rays meet a specular surface first, every light small): pt and bdpt reach "
          "it only by hitting a light, in rare bright samples a pilot does not see, so the "
          "Markov chains compete";
  } else if (!s.hasSpecular()) {
    wanted = hidden ? std::vector<Algorithm>{Algorithm::Bidirectional, Algorithm::PathTracing,
                                             Algorithm::PSSMLT}
                    : std::vector<Algorithm>{Algorithm::PathTracing, Algorithm::Bidirectional,
                                             Algorithm::PSSMLT};
    why = "no specular surfaces, " + lit + (hidden ? ": bdpt first" : ": pt first");
  } else {
    // In sight of the lights, pt reaches a caustic by sampling its BSDF into the light after the
    // specular bounce, as often as the light is wide seen from there. Under a room's ceiling
    // light that is often enough and pt's samples are cheaper (the tuning half's glass and metal
    // objects, and its glass ball in fog too thin to count, seeds 1-3: bdpt 1.12-1.26x pt's
    // error); the environment's sun is a few degrees of the sky, which bdpt's light subpaths
    // start from (pt 2.5-3.1x bdpt's error), and in fog before the camera bdpt's light subpaths
    // scatter in the medium and connect (fog-0: pt 1.22x bdpt's). docs/corpus.md, "pt or bdpt
    // first with specular surfaces".
    const bool fog = foggy(s);
    why = fog && s.someSpecularDiffuseSpecular()
              ? "specular surfaces seen through fog (" + percent(s.specularSeen) + " seen, " +
                    percent(s.specularLit) + " lit first; the fog takes " + percent(s.mediaSeen) +
                    " of the light along camera rays), "
              : "specular surfaces, but no specular-diffuse-specular light (" +
                    percent(s.specularSeen) + " seen, " + percent(s.specularLit) + " lit first), ";
    why += lit;
    if (hidden) {
      wanted = {Algorithm::MLT, Algorithm::Bidirectional, Algorithm::PSSMLT};
      why += ": mlt first";
    } else if (!s.environment && !fog) {
      wanted = {Algorithm::PathTracing, Algorithm::Bidirectional, Algorithm::PSSMLT};
      why += ": pt first";
    } else {
      wanted = {Algorithm::Bidirectional, Algorithm::PathTracing, Algorithm::PSSMLT};
      why += fog ? ": bdpt first (its light subpaths scatter in the fog)"
                 : ": bdpt first (its light subpaths start from the environment's sun)";
    }
  }
  for (Algorithm a : wanted) {
    if (usable(s, a)) plan->shortlist.push_back(a);
  }
  for (Algorithm a : s.usable) {
    if (std::find(wanted.begin(), wanted.end(), a) != wanted.end()) continue;
    std::string reason;
    if (a == Algorithm::PSSMLTOverPT) {
      reason = "pssmlt explores the same primary samples with every bidirectional strategy";
    } else if (a == Algorithm::ERPT) {
      reason = "its chains spread path-traced seeds, pt's noise redistributed";
    } else if (a == Algorithm::PathTracing && lightsInGlass) {
      reason =
          "reaches the light only by hitting it through the glass (5-36x bdpt's error on "
          "the corpus's lights in glass)";
    } else if (a == Algorithm::MLT && lightsInGlass) {
      reason = "1-4.5x bdpt's error on the corpus's lights in glass (docs/corpus.md)";
    } else if ((a == Algorithm::PathTracing || a == Algorithm::Bidirectional) && someSds) {
      reason = "fireflies from the specular-diffuse-specular light";
    } else if ((a == Algorithm::MMLT || a == Algorithm::MLT) && !hidden) {
      reason = "lights in sight: 3-35x the error of pt or bdpt on such scenes (docs/corpus.md)";
    } else if (a == Algorithm::MMLT || a == Algorithm::MLT) {
      reason = s.hasSpecular() ? "mlt's perturbations follow specular chains that its "
                                 "strategies must find anew (veach-ajar: 1.3x mlt's error)"
                               : "bdpt carries the light out of hiding with less (the boxed-in "
                                 "light: mlt 2.3-3x bdpt's error, mmlt 7-11x)";
    } else if (a == Algorithm::PathTracing) {
      reason = "lights hidden, specular surfaces: bdpt's light subpaths reach what it cannot";
    }
    plan->notShortlisted.push_back(std::string(algorithmName(a)) + ": " + reason);
  }
  plan->why = why;
}

}  // namespace

MutationMix plannedMutationMix(const SceneAnalysis& scene, const MutationMix& requested) {
  MutationMix mix = requested;
  if (!scene.hasSpecular()) {
    mix.multiChainPerturbation = 0;
    mix.manifoldPerturbation = 0;
  }
  return mix;
}

RenderPlan planRender(const SceneAnalysis& s, Algorithm requested, bool automatic,
                      const MutationMix& requestedMix, int requestedChains) {
  RenderPlan plan;
  plan.scene = s;
  plan.automatic = automatic;
  plan.requestedChains = requestedChains;
  plan.algorithm = requested;
  if (automatic) {
    shortlist(s, &plan);
    if (!plan.shortlist.empty()) plan.algorithm = plan.shortlist.front();
  }
  plan.mutationMix = plannedMutationMix(s, requestedMix);

  plan.choose(plan.algorithm);
  return plan;
}

void RenderPlan::choose(Algorithm chosen) {
  algorithm = chosen;
  parts.clear();
  const SceneAnalysis& s = scene;
  const bool mlt = algorithm == Algorithm::MLT;
  chains = 0;
  chainsReason.clear();
  if (isMarkovChain(algorithm) && someSdsRule(s)) {
    chains = requestedChains > 0 ? requestedChains : kSdsChains;
    if (requestedChains > 0)
      chainsReason = "requested; the plan's would be " + std::to_string(kSdsChains);
    else if (s.specularDiffuseSpecular())
      chainsReason =
          "specular-diffuse-specular light: a chain seldom leaves the caustic it starts on, so "
          "more and shorter chains spread what each finds (mlt's relative MSE on water-caustic "
          "at 30 s: 0.8 against 3.3 with 64)";
    else
      chainsReason =
          "some specular-diffuse-specular light: a chain that finds such a path holds it for "
          "thousands of mutations, so more and shorter chains spread what each finds (mmlt's "
          "relative MSE on veach-bidir at 30 s, seeds 1-4: at most 0.015 against up to 0.47 "
          "with 64)";
  }
  const std::string noSpecular = "no specular surfaces";
  auto mutation = [&](const char* name, double weight, const char* reason) {
    PlanPart p;
    p.name = name;
    p.enabled = weight > 0;
    if (!mlt) {
      p.enabled = false;
      p.reason = std::string("a mutation of mlt, not of ") + algorithmName(algorithm);
    } else if (!s.hasSpecular() && !p.enabled && reason) {
      p.reason = noSpecular + std::string(": ") + reason;
    } else {
      p.reason = p.enabled ? "weight " + number(weight) : "weight 0 in --mutation-mix";
    }
    parts.push_back(p);
  };
  // Not left out without specular surfaces: Veach's caustic perturbation covers (L|D) S* D E,
  // and with no S it perturbs D D E paths from the light side. Measured (docs/plan.md):
  // leaving it out of mlt on cornell-box gave 1.33x the relative MSE at equal time.
  mutation("caustic perturbation", mutationMix.causticPerturbation, nullptr);
  if (mlt && !s.hasSpecular() && mutationMix.causticPerturbation > 0)
    parts.back().reason += ", kept: it perturbs D D E paths too (1.33x the error without it)";
  mutation("multi-chain perturbation", mutationMix.multiChainPerturbation,
           "no chain of specular vertices between diffuse ones");
  mutation("manifold perturbation", mutationMix.manifoldPerturbation,
           "no specular chain for a manifold walk");

  // ManifoldNextEvent::active and covers: smooth specular shapes only.
  const int smoothSpecular = s.specularShapes - s.facetedSpecularShapes;
  PlanPart manifoldNee{"manifold next-event estimation", smoothSpecular > 0 && !s.lights.empty(),
                       ""};
  if (manifoldNee.enabled) {
    manifoldNee.reason =
        "the bootstrap connects diffuse vertices to lights through chains of up to four specular "
        "vertices";
    if (s.facetedSpecularShapes > 0)
      manifoldNee.reason += "; paths over faceted specular shapes (" +
                            std::to_string(s.facetedSpecularShapes) +
                            " here: flat-shaded and curved, every facet a solution of its own) "
                            "stay with BDPT's strategies, which under a small light find them "
                            "slowly (smooth vertex normals avoid it)";
  } else if (s.hasSpecular() && !s.lights.empty()) {
    manifoldNee.reason =
        "every specular shape is faceted (flat-shaded and curved): each facet holds its own "
        "solution, which a manifold walk finds only from a seed on it; BDPT keeps these paths";
  } else {
    manifoldNee.reason = noSpecular + ": the bootstrap never searches a specular vertex";
  }
  if (manifoldNee.enabled && !needsBootstrap(algorithm)) {
    manifoldNee.enabled = false;
    manifoldNee.reason = std::string(algorithmName(algorithm)) + " has no bootstrap";
  }
  parts.push_back(manifoldNee);
  // SeenEmission::separates: scenes without media, through a pinhole (render_job.cpp plans the
  // chains by it).
  const bool mediaInScene = s.homogeneousMedia + s.gridMedia > 0;
  PlanPart seen{"seen emission apart", mlt && !mediaInScene && !s.thinLens, ""};
  seen.reason = !mlt ? std::string("only mlt's chains leave it to its own sampler, not ") +
                           algorithmName(algorithm) + "'s"
                : mediaInScene
                    ? "media: the chains keep the lights they see (their edges carry transmittance)"
                : s.thinLens
                    ? "thin lens: the chains keep the lights they see (its sampler projects "
                      "through a pinhole)"
                    : "the lights the camera sees directly are sampled beside the chains (film "
                      "points and light points projected onto the film), not left to how many "
                      "chains start on them";
  parts.push_back(seen);
  parts.push_back({"lens sampling", s.thinLens,
                   s.thinLens ? "thin lens of radius " + number(s.lensRadius)
                              : "pinhole camera: every ray starts at the camera's point"});
  parts.push_back({"texture lookups", s.texturedBsdfs > 0,
                   s.texturedBsdfs > 0 ? std::to_string(s.texturedBsdfs) + " textured BSDF(s)"
                                       : "no textures: BSDFs are taken as the scene gives them"});
  parts.push_back({"escaped-path handling", s.environment,
                   s.environment
                       ? (s.environmentMap ? "an environment map" : "a constant environment")
                       : "no environment: a ray that leaves the scene carries nothing"});
  const int media = s.homogeneousMedia + s.gridMedia;
  parts.push_back({"medium tracking", media > 0,
                   media > 0
                       ? std::to_string(s.homogeneousMedia) + " homogeneous, " +
                             std::to_string(s.gridMedia) + " grid medium/media"
                       : "no media: rays travel in vacuum, no transmittance or free flights"});
}

std::vector<std::string> RenderPlan::describe() const {
  std::vector<std::string> out;
  const SceneAnalysis& s = scene;
  out.push_back("surfaces: " + std::to_string(s.specularShapes) + " specular (" +
                number(s.specularArea) + " area), " + std::to_string(s.glossyShapes) +
                " glossy (alpha <= " + number(kGlossyAlpha) + ", " + number(s.glossyArea) +
                " area), " + std::to_string(s.diffuseShapes) + " diffuse or rough (" +
                number(s.diffuseArea) + " area)");
  if (s.hasSpecular()) {
    out.push_back("specular surfaces meet " + percent(s.specularSeen) + " of camera rays and " +
                  percent(s.specularLit) + " of light rays first (" + std::to_string(s.probeRays) +
                  " probe rays)");
  }
  out.push_back("lights: " + std::to_string(s.lights.size()) +
                (s.smallLights ? " (all small: under " + percent(kSmallLight) +
                                     " of the scene's diameter across)"
                               : ""));
  if (!s.lights.empty())
    out.push_back("  a light sample is unblocked from " + percent(s.directlyLit) +
                  " of the surfaces the camera sees first");
  for (const LightSummary& l : s.lights) {
    std::string line = std::string("  ") + lightKindName(l.kind);
    if (l.kind == LightSummary::Kind::Area)
      line += ", area " + number(l.area) + " (" + percent(l.size) + " of the diameter across)";
    line += ", power " + number(l.power) + " (" + percent(l.share) + ")";
    if (!l.origin.empty()) line += ", " + l.origin;
    out.push_back(line);
  }
  out.push_back(std::string("camera: ") +
                (s.thinLens ? "thin lens, radius " + number(s.lensRadius) : "pinhole"));
  out.push_back("textures: " + std::to_string(s.texturedBsdfs) + " textured BSDF(s)");
  out.push_back(std::string("shading normals: ") + (s.strictNormals ? "strict, " : "lax, ") +
                std::to_string(s.smoothShapes) + " smooth-shaded shape(s)" +
                (s.strictNormals && s.smoothShapes > 0
                     ? " (paths whose directions a shape's two normals put on different sides "
                       "end there; --shading-normals lax keeps them)"
                     : ""));
  out.push_back(std::string("environment: ") +
                (s.environment ? (s.environmentMap ? "map" : "constant") : "none"));
  out.push_back("media: " + std::to_string(s.homogeneousMedia) + " homogeneous, " +
                std::to_string(s.gridMedia) + " grid" +
                (s.hasMedia() ? "; they take " + percent(s.mediaSeen) +
                                    " of the light along camera rays before the first surface"
                              : ""));
  for (const auto& [name, share] : s.mediaLookedThrough)
    out.push_back("  the camera looks through " + name + " on " + percent(share) + " of its rays");
  if (!applied) {
    out.push_back(std::string("algorithm: ") + algorithmName(algorithm) +
                  " (--no-plan: every part the settings name, none left out)");
    return out;
  }
  out.push_back(std::string("algorithm: ") + algorithmName(algorithm) +
                (automatic ? " (auto)" : " (requested)"));
  if (automatic) {
    std::string list;
    for (Algorithm a : shortlist) list += std::string(list.empty() ? "" : ", ") + algorithmName(a);
    out.push_back("  candidates: " + list + "; " + why);
    for (const std::string& n : notShortlisted) out.push_back("  not a candidate: " + n);
    for (const PilotFigure& p : pilot) {
      std::string line = std::string("  pilot ") + algorithmName(p.algorithm) + ": ";
      if (p.estimatedRelMse < 0) {
        line += p.failure;
      } else {
        line += number(p.seconds) + " s (after a " + number(p.bootstrapSeconds) +
                " s bootstrap), estimated relMSE " + number(p.estimatedRelMse) +
                (p.crossRelMse >= 0 ? ", from the others' images " + number(p.crossRelMse) : "") +
                ", score (relMSE x s) " + number(p.score);
      }
      out.push_back(line);
    }
  }
  if (algorithm == Algorithm::MLT) out.push_back("mutations: " + formatMutationMix(mutationMix));
  if (chains > 0) out.push_back("chains: " + std::to_string(chains) + " (" + chainsReason + ")");
  for (const PlanPart& p : parts) {
    out.push_back(std::string(p.enabled ? "  in: " : "  left out: ") + p.name + " (" + p.reason +
                  ")");
  }
  return out;
}

}  // namespace farm
