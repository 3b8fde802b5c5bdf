#include "common/film/splat_buffer.h"

#include <algorithm>
#include <cmath>

namespace farm {

SplatBuffer::SplatBuffer(int width, int height, FilterType filter)
    : width_(width), height_(height), filter_(filter), data_(size_t(width) * height * 3, 0.0f) {}

void SplatBuffer::clear() {
  std::fill(data_.begin(), data_.end(), 0.0f);
}

void SplatBuffer::add(const Vec2f& film, const Spectrum& v, float scale) {
  auto put = [&](int x, int y, float w) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_ || w <= 0) return;
    float* p = &data_[(size_t(y) * width_ + x) * 3];
    float s = w * scale;
    p[0] += v.x * s, p[1] += v.y * s, p[2] += v.z * s;
  };
  if (filter_ == FilterType::Box) {
    put(int(std::floor(film.x)), int(std::floor(film.y)), 1.0f);
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
