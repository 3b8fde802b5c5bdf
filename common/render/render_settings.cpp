#include "common/render/render_settings.h"

#include <cmath>
#include <sstream>
#include <string>

namespace farm {

const char* shadingNormalsName(ShadingNormals s) {
  switch (s) {
    case ShadingNormals::Strict:
      return "strict";
    case ShadingNormals::Lax:
      return "lax";
    case ShadingNormals::Scene:
      break;
  }
  return "scene";
}

bool parseShadingNormals(const std::string& name, ShadingNormals* out) {
  for (ShadingNormals s : {ShadingNormals::Scene, ShadingNormals::Strict, ShadingNormals::Lax}) {
    if (name == shadingNormalsName(s)) {
      *out = s;
      return true;
    }
  }
  return false;
}

std::string RenderSettings::validate() const {
  std::ostringstream err;
  constexpr int kMaxSide = 1 << 16;
  constexpr int64_t kMaxPixels = int64_t(1) << 28;
  if (width < 0 || height < 0 || width > kMaxSide || height > kMaxSide) {
    err << "film size " << width << "x" << height << " is out of range (1.." << kMaxSide << ")";
  } else if (int64_t(width) * height > kMaxPixels) {
    err << "film size " << width << "x" << height << " has more than 2^28 pixels";
  } else if (samplesPerPixel < 1 || samplesPerPixel > (int64_t(1) << 24)) {
    err << "samples per pixel must be in 1.." << (1 << 24) << ", not " << samplesPerPixel;
  } else if (mutationsPerPixel < 1 || mutationsPerPixel > (int64_t(1) << 24)) {
    err << "mutations per pixel must be in 1.." << (1 << 24) << ", not " << mutationsPerPixel;
  } else if (!std::isfinite(timeBudgetSeconds) || timeBudgetSeconds < 0 ||
             timeBudgetSeconds > 30 * 24 * 3600.0) {
    err << "time budget must be a number of seconds between 0 and 30 days, not "
        << timeBudgetSeconds;
  } else if (maxDepth < -1 || maxDepth > 4096) {
    err << "--max-depth must be -1 (unbounded), 0 (the scene's) or 1..4096, not " << maxDepth;
  } else if (bootstrapSamples < 0 || bootstrapSamples > kMaxBootstrapSamples) {
    err << "--bootstrap-candidates must be in 0.." << kMaxBootstrapSamples << ", not "
        << bootstrapSamples;
  } else if (numChains < 0 || numChains > 1 << 20) {
    err << "number of chains must be in 0.." << (1 << 20) << ", not " << numChains;
  } else if (!(largeStepProbability > 0 && largeStepProbability <= 1)) {
    err << "large-step probability must be in (0, 1], not " << largeStepProbability;
  } else if (std::string mix = validateMutationMix(mutationMix); !mix.empty()) {
    err << mix;
  } else if (!(erptChains > 0 && erptChains <= 1024)) {
    err << "ERPT chains per seed must be in (0, 1024], not " << erptChains;
  } else if (erptLength < 1 || erptLength > 1 << 20) {
    err << "ERPT chain length must be in 1.." << (1 << 20) << " mutations, not " << erptLength;
  } else if (flushInterval < 0 || flushInterval > (int64_t(1) << 40)) {
    err << "--flush-every must be 0 (one film's worth) or up to 2^40, not " << flushInterval;
  } else if (mediumSamples < 1 || mediumSamples > 1024) {
    err << "--medium-samples must be in 1..1024 estimates, not " << mediumSamples;
  } else if (mediumMarchSteps < 0 || mediumMarchSteps > 1 << 16) {
    err << "--medium-march must be in 0.." << (1 << 16) << " steps, not " << mediumMarchSteps;
  } else if (!std::isfinite(untilError) || untilError < 0) {
    err << "--until-error must be a relative MSE >= 0 (0: none), not " << untilError;
  } else if (errorGroups < 0 || errorGroups > 64) {
    err << "--error-groups must be in 0..64 (0: the default), not " << errorGroups;
  } else if (autoAlgorithm && ignorePlan) {
    err << "--algorithm auto is the plan's choice: it cannot go with --no-plan";
  } else if (pilot && !autoAlgorithm) {
    err << "--pilot ranks auto's candidates: it needs --algorithm auto";
  } else if (combineLargeSteps && !autoAlgorithm && !isPrimarySampleSpace(algorithm)) {
    err << "--combine-large-steps weights large steps into a chain: pssmlt, pssmlt-pt or mmlt, "
           "not "
        << algorithmName(algorithm);
  } else if (pixelAllocation && (autoAlgorithm || (algorithm != Algorithm::PathTracing &&
                                                   algorithm != Algorithm::Bidirectional))) {
    err << "a pixel allocation places independent samples: pt or bdpt, not "
        << (autoAlgorithm ? "auto" : algorithmName(algorithm));
  } else if (pixelAllocation && ((width != 0 && width != pixelAllocation->width()) ||
                                 (height != 0 && height != pixelAllocation->height()))) {
    err << "the pixel allocation is for a film of " << pixelAllocation->width() << "x"
        << pixelAllocation->height() << ", the job's is " << (width ? std::to_string(width) : "?")
        << "x" << (height ? std::to_string(height) : "?");
  } else if (errorGroups == 1 && untilError > 0) {
    err << "--until-error needs an error estimate, which --error-groups 1 turns off";
  }
  return err.str();
}

}  // namespace farm
