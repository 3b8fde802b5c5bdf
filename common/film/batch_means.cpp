#include "common/film/batch_means.h"

#include <algorithm>
#include <cmath>

#include "common/film/neighbour_mean.h"

namespace farm {

namespace {

// r^2 is averaged over each pixel's kNeighbourhood^2 window (neighbour_mean.h).
constexpr int kNeighbourhood = 9;

}  // namespace

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
  if (count != size_t(image.width) * size_t(image.height) * 3)
    return fail("the image's values do not fill its width and height");
  for (const Image& g : groups) {
    if (g.width != image.width || g.height != image.height || g.rgb.size() != count)
      return fail("the groups' images differ in size from the image");
  }
  const double zRel = std::isfinite(zRelativeVariance) ? std::max(0.0, zRelativeVariance) : 0.0;
  // Per channel value: the variance of the image (the groups' spread) and an unbiased estimate
  // of r^2 from products of different groups' values, E[x_g x_h] = r^2 for g != h (independent
  // groups, each unbiased): ((sum_g W_g x_g)^2 - sum_g W_g^2 x_g^2) / sum_{g != h} W_g W_h.
  double sumW2 = 0;
  for (double w : work) sumW2 += w * w;
  const double pairWeight = total * total - sumW2;
  std::vector<double> variance(count), square(count);
  for (size_t i = 0; i < count; ++i) {
    const double x = image.rgb[i];
    double spread = 0, weighted = 0, weightedSq = 0;
    for (size_t g = 0; g < G; ++g) {
      const double v = groups[g].rgb[i];
      spread += work[g] * (v - x) * (v - x);
      weighted += work[g] * v;
      weightedSq += work[g] * work[g] * v * v;
    }
    variance[i] = spread / (double(G - 1) * total) + x * x * zRel;
    square[i] = std::max(0.0, (weighted * weighted - weightedSq) / pairWeight);
  }
  // The reference's r^2 in the denominator is taken as the mean of that estimate over the
  // pixel's neighbours (kNeighbourhood^2 - 1 of them, fewer at the border), not the pixel's own.
  // One pixel's groups cannot tell a firefly (one group far above the rest) from light that
  // arrives in rare bright samples (most groups below the mean, some far above): its own
  // estimate, or the groups' median, then falls far below r^2 wherever the image is still
  // made of rare samples, and the estimate rises by as much (veach-ajar at 4-16 samples a
  // pixel: 5-23x its measured error with the median). Its neighbours' light is r^2's with the
  // rare samples averaged out, and leaving the pixel out keeps its own firefly out of the
  // denominator that should weigh it. The cost is where r^2 bends within the window: a
  // smooth image's dark troughs take their brighter neighbours' r^2 (-1.7% on the unit test's
  // image, batch_means_test.cpp).
  const std::vector<double> neighbours =
      neighbourMean(square, image.width, image.height, kNeighbourhood);
  double sumRel = 0, sumSq = 0;
  for (size_t i = 0; i < count; ++i) {
    sumRel += variance[i] / (neighbours[i] + 1e-2);
    sumSq += variance[i];
  }
  out->relMse = sumRel / double(count);
  out->rmse = std::sqrt(sumSq / double(count));
  return true;
}

}  // namespace farm
