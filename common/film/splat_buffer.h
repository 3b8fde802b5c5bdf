#pragma once
// A film that receives splats at continuous film positions and spreads each over the pixels of
// the reconstruction filter. Filters are normalized (their weights over all pixels add up to
// one), so a splat's total value is kept: what MLT's normalization by Z relies on. The gaussian
// is normalized per splat, by the sum of its weights over every pixel centre in reach (those off
// the film included): pixel j then sees h_j(x) = g(x - c_j) / sum_k g(x - c_k), which
// integrates to one over the plane, the sum being periodic in x with a period of one pixel.
#include <cmath>
#include <cstdint>
#include <vector>

#include "common/math/vec.h"
#include "common/scene/scene_description.h"

namespace farm {

struct Splat {
  Vec2f film;      // pixels
  Spectrum value;  // already scaled to the estimator (see Camera for the A_px factor)
};

// Splat values that must not reach the image (Veach's estimators are finite and non-negative),
// counted by cause where they are made, so that a job can say what went wrong and how often.
struct InvalidSplats {
  int64_t nan = 0;       // a NaN in any channel
  int64_t infinite = 0;  // otherwise an infinity
  int64_t negative = 0;  // otherwise a negative channel
  int64_t total() const { return nan + infinite + negative; }
  // Counts `value` when it is not a valid splat; true when it is valid.
  bool check(const Spectrum& value) {
    if (isValidRadiance(value)) return true;
    if (std::isnan(value.x) || std::isnan(value.y) || std::isnan(value.z))
      ++nan;
    else if (!isFinite(value))
      ++infinite;
    else
      ++negative;
    return false;
  }
  InvalidSplats& operator+=(const InvalidSplats& o) {
    nan += o.nan, infinite += o.infinite, negative += o.negative;
    return *this;
  }
};

// The reconstruction filter of a camera.
struct PixelFilter {
  FilterType type = FilterType::Tent;
  float radius = 2, alpha = 2;  // Gaussian
  static PixelFilter of(const CameraDescription& camera) {
    return {camera.filter, camera.filterRadius, camera.filterAlpha};
  }
};

// The share of pixel i's filter (along one axis) that lies on a film of n pixels: one but within
// the filter's reach of the edges. Dividing by it makes border pixels the filter-weighted
// average renderers report (no dark rim).
double pixelFilterMassInside(const PixelFilter& filter, int i, int n);

class SplatBuffer {
 public:
  SplatBuffer(int width, int height, const PixelFilter& filter);

  void add(const Vec2f& film, const Spectrum& value, float scale = 1.0f);
  void clear();
  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<double>& data() const { return data_; }
  std::vector<double>& data() { return data_; }

 private:
  int width_, height_;
  PixelFilter filter_;
  // 3 values per pixel, summed in double: a flush may hold 2^20 and more splats, and Markov
  // chains pile theirs onto few pixels, where float sums would drop the increments below half
  // an ulp of what is there.
  std::vector<double> data_;
};

}  // namespace farm
