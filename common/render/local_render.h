#pragma once
// Runs a whole RenderJob in this process (bootstrap, every chain on the TBB pool, sums in
// double) with no coordinator: what the statistical tests and benchmarks of common/ use.
// `farm render` goes through the coordinator core instead, with the same chains. Under a time
// budget the chains take turns of one flush each, so that they advance evenly.
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/render/render_job.h"

namespace farm {

struct LocalRenderResult {
  Image image;
  BootstrapResult bootstrap;
  int64_t work = 0;        // mutations or samples
  int64_t rays = 0;        // traced for that work
  InvalidSplats rejected;  // splats dropped at the source, by cause
  double seconds = 0;
  // Per chain (work unit), the sum of each channel over all its splats: the units are
  // independent, so their spread between two renders measures the variance of sums over the
  // image even where one unit's splats spread over many pixels (MLT, ERPT).
  std::vector<std::array<double, 3>> chainTotals;
  std::vector<int64_t> chainWork;  // per chain, mutations or samples
  // Per error group (ChainSpec::errorGroup), the image of its chains alone (their splats at the
  // image's scale for their own work): independent estimates of the image but for the
  // bootstrap's Z, which they share, so that their spread gives the standard error of the
  // image's sum over any region.
  std::vector<Image> groupImages;
  std::map<std::string, MutationTally> tallies;  // proposals and acceptances by kind
  // The chains' large steps: the image is scaled by bootstrap.normalizationWith(largeSteps).
  LargeStepSums largeSteps;
};

LocalRenderResult renderLocally(const RenderJob& job);

}  // namespace farm
