#include "common/film/batch_means.h"

#include <algorithm>
#include <cmath>

#include "common/film/neighbour_mean.h"

namespace farm {

namespace {

// r^2 is averaged over each pixel's kNeighbourhood^2 window (neighbour_mean.h).
constexpr int kNeighbourhood = 9;

}  // namespace

void ImageFilms::rows(size_t g, int y0, int y1, float* out) const {
  const Image& from = g < groups_.size() ? groups_[g] : image_;
  const size_t row = size_t(from.width) * 3;
  std::copy(from.rgb.begin() + std::ptrdiff_t(size_t(y0) * row),
            from.rgb.begin() + std::ptrdiff_t(size_t(y1) * row), out);
}

bool estimateError(const ErrorFilms& films, const std::vector<double>& work,
                   double zRelativeVariance, ErrorEstimate* out, std::string* error, int bandRows) {
  auto fail = [&](const std::string& why) {
    if (error) *error = why;
    return false;
  };
  const size_t G = films.groups();
  if (G < 2) return fail("an estimate needs at least two groups, not " + std::to_string(G));
  if (work.size() != G) return fail("one work count per group");
  double total = 0;
  for (double w : work) {
    if (!(w > 0) || !std::isfinite(w)) return fail("a group without work");
    total += w;
  }
  const int width = films.width(), height = films.height();
  if (width <= 0 || height <= 0) return fail("an empty image");
  const double zRel = std::isfinite(zRelativeVariance) ? std::max(0.0, zRelativeVariance) : 0.0;
  double sumW2 = 0;
  for (double w : work) sumW2 += w * w;
  const double pairWeight = total * total - sumW2;
  // Bands of rows, each read with the neighbour window's rows above and below it: a pixel's
  // window then lies inside its band's rows, clipped where the image's border clips it.
  const int r = kNeighbourhood / 2;
  const int band = std::max(1, bandRows);
  const size_t row = size_t(width) * 3;
  std::vector<std::vector<float>> groups(G);
  std::vector<float> image;
  std::vector<double> variance, square;
  double sumRel = 0, sumSq = 0;
  for (int y0 = 0; y0 < height; y0 += band) {
    const int y1 = std::min(height, y0 + band);
    const int ya = std::max(0, y0 - r), yb = std::min(height, y1 + r);
    const size_t count = size_t(yb - ya) * row;
    image.resize(count);
    films.rows(G, ya, yb, image.data());
    for (size_t g = 0; g < G; ++g) {
      groups[g].resize(count);
      films.rows(g, ya, yb, groups[g].data());
    }
    // Per channel value: the variance of the image (the groups' spread) and an unbiased
    // estimate of r^2 from products of different groups' values, E[x_g x_h] = r^2 for g != h
    // (independent groups, each unbiased):
    // ((sum_g W_g x_g)^2 - sum_g W_g^2 x_g^2) / sum_{g != h} W_g W_h.
    variance.resize(count);
    square.resize(count);
    for (size_t i = 0; i < count; ++i) {
      const double x = image[i];
      double spread = 0, weighted = 0, weightedSq = 0;
      for (size_t g = 0; g < G; ++g) {
        const double v = groups[g][i];
        spread += work[g] * (v - x) * (v - x);
        weighted += work[g] * v;
        weightedSq += work[g] * work[g] * v * v;
      }
      variance[i] = spread / (double(G - 1) * total) + x * x * zRel;
      square[i] = std::max(0.0, (weighted * weighted - weightedSq) / pairWeight);
    }
    // The reference's r^2 in the denominator is taken as the mean of that estimate over the
    // pixel's neighbours (kNeighbourhood^2 - 1 of them, fewer at the border), not the pixel's
    // own. One pixel's groups cannot tell a firefly (one group far above the rest) from light
    // that arrives in rare bright samples (most groups below the mean, some far above): its own
    // estimate, or the groups' median, then falls far below r^2 wherever the image is still
    // made of rare samples, and the estimate rises by as much (veach-ajar at 4-16 samples a
    // pixel: 5-23x its measured error with the median). Its neighbours' light is r^2's with the
    // rare samples averaged out, and leaving the pixel out keeps its own firefly out of the
    // denominator that should weigh it. The cost is where r^2 bends within the window: a
    // smooth image's dark troughs take their brighter neighbours' r^2 (-1.7% on the unit
    // test's image, batch_means_test.cpp).
    const std::vector<double> neighbours = neighbourMean(square, width, yb - ya, kNeighbourhood);
    for (size_t i = size_t(y0 - ya) * row; i < size_t(y1 - ya) * row; ++i) {
      sumRel += variance[i] / (neighbours[i] + 1e-2);
      sumSq += variance[i];
    }
  }
  const double values = double(width) * double(height) * 3;
  out->relMse = sumRel / values;
  out->rmse = std::sqrt(sumSq / values);
  return true;
}

bool estimateError(const std::vector<Image>& groups, const std::vector<double>& work,
                   const Image& image, double zRelativeVariance, ErrorEstimate* out,
                   std::string* error, int bandRows) {
  auto fail = [&](const std::string& why) {
    if (error) *error = why;
    return false;
  };
  const size_t count = image.rgb.size();
  if (count == 0) return fail("an empty image");
  if (count != size_t(image.width) * size_t(image.height) * 3)
    return fail("the image's values do not fill its width and height");
  for (const Image& g : groups) {
    if (g.width != image.width || g.height != image.height || g.rgb.size() != count)
      return fail("the groups' images differ in size from the image");
  }
  return estimateError(ImageFilms(groups, image), work, zRelativeVariance, out, error, bandRows);
}

}  // namespace farm
