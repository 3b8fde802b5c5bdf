#include "common/film/cross_estimate.h"

#include <algorithm>

#include "common/film/neighbour_mean.h"

namespace farm {

std::vector<double> crossEstimates(const std::vector<const Image*>& images) {
  const size_t n = images.size();
  if (n < 3) return {};
  const size_t size = images[0]->rgb.size();
  for (const Image* image : images)
    if (image->width != images[0]->width || image->height != images[0]->height || size == 0)
      return {};
  // The reference stand-in: the images' mean, over each pixel's neighbours without the pixel
  // itself (as batch_means.cpp takes r^2). The pixel's own mean would hold each image's noise
  // there, and the denominator r^2 would shrink a firefly's squared error to about n^2 (a
  // pixel with a tenfold outlier would count for little more than one with none).
  const int w = images[0]->width, h = images[0]->height;
  if (size_t(w) * size_t(h) * 3 != size) return {};
  std::vector<double> mean(size, 0.0);
  for (const Image* image : images)
    for (size_t k = 0; k < size; ++k) mean[k] += image->rgb[k] / double(n);
  const std::vector<double> r = neighbourMean(mean, w, h, 3);
  std::vector<std::vector<double>> d(n, std::vector<double>(n, 0.0));
  for (size_t a = 0; a < n; ++a)
    for (size_t b = a + 1; b < n; ++b) {
      double sum = 0;
      for (size_t k = 0; k < size; ++k) {
        const double diff = double(images[a]->rgb[k]) - images[b]->rgb[k];
        sum += diff * diff / (r[k] * r[k] + 0.01);
      }
      d[a][b] = d[b][a] = sum / double(size);
    }
  std::vector<double> estimates(n, 0.0);
  for (size_t a = 0; a < n; ++a) {
    std::vector<double> hats;
    for (size_t b = 0; b < n; ++b)
      for (size_t c = b + 1; c < n; ++c)
        if (b != a && c != a) hats.push_back(0.5 * (d[a][b] + d[a][c] - d[b][c]));
    std::nth_element(hats.begin(), hats.begin() + hats.size() / 2, hats.end());
    estimates[a] = std::max(0.0, hats[hats.size() / 2]);
  }
  return estimates;
}

}  // namespace farm
