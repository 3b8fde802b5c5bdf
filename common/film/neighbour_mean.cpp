#include "common/film/neighbour_mean.h"

#include <algorithm>

namespace farm {

std::vector<double> neighbourMean(const std::vector<double>& values, int width, int height,
                                  int window) {
  const size_t W = size_t(width) + 1, H = size_t(height) + 1;
  std::vector<double> sum(W * H * 3, 0.0);  // sum[(y, x, c)] over pixels above and left of it
  for (size_t y = 1; y < H; ++y)
    for (size_t x = 1; x < W; ++x)
      for (size_t c = 0; c < 3; ++c)
        sum[(y * W + x) * 3 + c] = values[((y - 1) * size_t(width) + x - 1) * 3 + c] +
                                   sum[((y - 1) * W + x) * 3 + c] + sum[(y * W + x - 1) * 3 + c] -
                                   sum[((y - 1) * W + x - 1) * 3 + c];
  std::vector<double> out(values.size());
  const int r = window / 2;
  for (int y = 0; y < height; ++y) {
    const size_t y0 = size_t(std::max(0, y - r)), y1 = size_t(std::min(height, y + r + 1));
    for (int x = 0; x < width; ++x) {
      const size_t x0 = size_t(std::max(0, x - r)), x1 = size_t(std::min(width, x + r + 1));
      const double n = double((y1 - y0) * (x1 - x0)) - 1;
      for (size_t c = 0; c < 3; ++c) {
        const size_t i = (size_t(y) * size_t(width) + size_t(x)) * 3 + c;
        const double window = sum[(y1 * W + x1) * 3 + c] - sum[(y0 * W + x1) * 3 + c] -
                              sum[(y1 * W + x0) * 3 + c] + sum[(y0 * W + x0) * 3 + c];
        out[i] = n > 0 ? (window - values[i]) / n : values[i];
      }
    }
  }
  return out;
}

}  // namespace farm
