#pragma once
// A film that receives splats at continuous film positions and spreads each over the pixels of
// the reconstruction filter. Filters are normalized (their weights over all pixels add up to
// one), so a splat's total value is kept: what MLT's normalization by Z relies on.
#include <cstdint>
#include <vector>

#include "common/math/vec.h"
#include "common/scene/scene_description.h"

namespace farm {

struct Splat {
  Vec2f film;      // pixels
  Spectrum value;  // already scaled to the estimator (see Camera for the A_px factor)
};

class SplatBuffer {
 public:
  SplatBuffer(int width, int height, FilterType filter);

  void add(const Vec2f& film, const Spectrum& value, float scale = 1.0f);
  void clear();
  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<float>& data() const { return data_; }
  std::vector<float>& data() { return data_; }

 private:
  int width_, height_;
  FilterType filter_;
  std::vector<float> data_;  // 3 floats per pixel
};

}  // namespace farm
