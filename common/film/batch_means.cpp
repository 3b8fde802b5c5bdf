#include "common/film/batch_means.h"

#include <algorithm>
#include <cmath>

namespace farm {

bool estimateError(const std::vector<Image>& groups, const std::vector<double>& work,
                   const Image& image, double zRelativeVariance, ErrorEstimate* out,
                   std::string* error) {
  auto fail = [&](const std::string& why) {
    if (error) *error = why;
    return false;
  };
  const size_t G = groups.size();
  if (G < 2) return fail("an estimate needs at least two groups, not " + std::to_string(G));
  if (work.size() != G) return fail("one work count per group");
  double total = 0;
  for (double w : work) {
    if (!(w > 0) || !std::isfinite(w)) return fail("a group without work");
    total += w;
  }
  const size_t count = image.rgb.size();
  if (count == 0) return fail("an empty image");
  for (const Image& g : groups) {
    if (g.width != image.width || g.height != image.height || g.rgb.size() != count)
      return fail("the groups' images differ in size from the image");
  }
  const double zRel = std::isfinite(zRelativeVariance) ? std::max(0.0, zRelativeVariance) : 0.0;
  double sumRel = 0, sumSq = 0;
  std::vector<double> values(G);
  for (size_t i = 0; i < count; ++i) {
    const double x = image.rgb[i];
    double spread = 0;
    for (size_t g = 0; g < G; ++g) {
      const double d = double(groups[g].rgb[i]) - x;
      spread += work[g] * d * d;
      values[g] = groups[g].rgb[i];
    }
    const double variance = spread / (double(G - 1) * total) + x * x * zRel;
    // The groups' median stands in for the reference: unlike the image, it does not carry a
    // firefly of one group into the denominator that should weigh it.
    std::sort(values.begin(), values.end());
    const double median = G % 2 ? values[G / 2] : 0.5 * (values[G / 2 - 1] + values[G / 2]);
    sumRel += variance / (median * median + 1e-2);
    sumSq += variance;
  }
  out->relMse = sumRel / double(count);
  out->rmse = std::sqrt(sumSq / double(count));
  return true;
}

}  // namespace farm
