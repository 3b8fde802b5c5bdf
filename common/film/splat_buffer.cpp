#include "common/film/splat_buffer.h"

#include <algorithm>
#include <cmath>

namespace farm {

namespace {

constexpr int kMaxGaussianReach = 34;  // pixel centres per axis: radius up to 16

// In double: for small alpha the two exponentials are close to one and to each other.
double gaussian1d(const PixelFilter& f, double d) {
  const double alpha = f.alpha, r = f.radius;
  return std::max(0.0, std::exp(-alpha * d * d) - std::exp(-alpha * r * r));
}

// The pixel centres i + 0.5 within the gaussian's reach of x, from *first on, with their
// weights normalized by their sum; their count (0 when none).
int gaussianWeights(const PixelFilter& f, float x, int* first, float* weights) {
  const int lo = int(std::ceil(x - 0.5f - f.radius)), hi = int(std::floor(x - 0.5f + f.radius));
  int count = 0;
  double w[kMaxGaussianReach], sum = 0;
  for (int i = lo; i <= hi && count < kMaxGaussianReach; ++i, ++count) {
    w[count] = gaussian1d(f, double(x) - (i + 0.5));
    sum += w[count];
  }
  *first = lo;
  if (!(sum > 0)) {
    // No centre with a weight (the filter underflowed between two of them): the nearest pixel
    // takes the splat, so that it still counts once and every pixel's filter still integrates
    // to one.
    *first = int(std::floor(x));
    weights[0] = 1;
    return 1;
  }
  for (int k = 0; k < count; ++k) weights[k] = float(w[k] / sum);
  return count;
}

}  // namespace

double pixelFilterMassInside(const PixelFilter& filter, int i, int n) {
  switch (filter.type) {
    case FilterType::Box:
      return 1;
    case FilterType::Tent: {
      double mass = 1;
      if (i == 0) mass -= 0.125;  // integral of the tent from 0.5 to 1 from the centre
      if (i == n - 1) mass -= 0.125;
      return mass;
    }
    case FilterType::Gaussian: {
      const double c = i + 0.5, r = filter.radius;
      if (c - r >= 0 && c + r <= n) return 1;
      // The integral of h_i over the film's [0, n), by the midpoint rule at 256 steps a pixel.
      const double a = std::max(0.0, c - r), b = std::min(double(n), c + r);
      const int steps = std::max(1, int(std::ceil((b - a) * 256)));
      const double dx = (b - a) / steps;
      double mass = 0;
      float w[kMaxGaussianReach];
      for (int k = 0; k < steps; ++k) {
        int first;
        const int count = gaussianWeights(filter, float(a + (k + 0.5) * dx), &first, w);
        if (i - first >= 0 && i - first < count) mass += w[i - first] * dx;
      }
      return mass;
    }
  }
  return 1;
}

SplatBuffer::SplatBuffer(int width, int height, const PixelFilter& filter)
    : width_(width), height_(height), filter_(filter), data_(size_t(width) * height * 3, 0.0f) {}

void SplatBuffer::clear() {
  std::fill(data_.begin(), data_.end(), 0.0f);
}

void SplatBuffer::add(const Vec2f& film, const Spectrum& v, float scale) {
  // Far outside the film (or not a number) a splat reaches no pixel; the casts below need it.
  if (!(std::fabs(film.x) < 1e7f && std::fabs(film.y) < 1e7f)) return;
  auto put = [&](int x, int y, float w) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_ || w <= 0) return;
    double* p = &data_[(size_t(y) * width_ + x) * 3];
    const double s = double(w) * double(scale);
    p[0] += double(v.x) * s, p[1] += double(v.y) * s, p[2] += double(v.z) * s;
  };
  if (filter_.type == FilterType::Box) {
    put(int(std::floor(film.x)), int(std::floor(film.y)), 1.0f);
    return;
  }
  if (filter_.type == FilterType::Gaussian) {
    float wx[kMaxGaussianReach], wy[kMaxGaussianReach];
    int x0, y0;
    const int nx = gaussianWeights(filter_, film.x, &x0, wx);
    const int ny = gaussianWeights(filter_, film.y, &y0, wy);
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) put(x0 + i, y0 + j, wx[i] * wy[j]);
    return;
  }
  // Tent of radius one pixel around each pixel centre (x + 0.5): separable, its weights over
  // the (up to) four pixels it touches sum to one.
  float fx = film.x - 0.5f, fy = film.y - 0.5f;
  int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
  float dx = fx - x0, dy = fy - y0;
  put(x0, y0, (1 - dx) * (1 - dy));
  put(x0 + 1, y0, dx * (1 - dy));
  put(x0, y0 + 1, (1 - dx) * dy);
  put(x0 + 1, y0 + 1, dx * dy);
}

}  // namespace farm
