#include "common/film/pixel_allocation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "common/math/bytes.h"

namespace farm {

namespace {

constexpr uint32_t kMagic = 0x41584950;  // "PIXA"
constexpr uint32_t kVersion = 1;
// A film of at most 2^16 pixels a side and cells of at most that: no product overflows.
constexpr int kMaxSide = 1 << 16;
// 5 bytes a cell, at most 320 KiB (a 4K film in cells of 16): a job's allocation goes to each
// worker once, with a lease, well under its message limit (proto/wire_limits.h).
constexpr size_t kMaxCells = size_t(1) << 16;

}  // namespace

int PixelAllocation::cellSizeFor(int width, int height, int maxCells) {
  if (width <= 0 || height <= 0 || maxCells <= 0)
    throw std::invalid_argument("pixel allocation: film and cell count must be positive");
  int size = 1;
  while (int64_t((width + size - 1) / size) * ((height + size - 1) / size) > maxCells) ++size;
  return size;
}

PixelAllocation PixelAllocation::byError(const std::vector<Image>& groups, bool bidirectional,
                                         int radius, double floor, int maxCells) {
  if (groups.size() < 2)
    throw std::invalid_argument("pixel allocation: the pilot needs two images or more");
  const int width = groups[0].width, height = groups[0].height;
  for (const Image& g : groups) {
    if (g.width != width || g.height != height || g.rgb.size() != size_t(width) * height * 3)
      throw std::invalid_argument("pixel allocation: the pilot's images differ in size");
  }
  const size_t pixels = size_t(width) * height;
  const double n = double(groups.size());
  std::vector<double> error(pixels, 0.0);
  for (size_t p = 0; p < pixels; ++p) {
    for (int c = 0; c < 3; ++c) {
      double sum = 0, sumSquares = 0;
      for (const Image& g : groups) {
        const double v = g.rgb[3 * p + size_t(c)];
        sum += v;
        sumSquares += v * v;
      }
      const double mean = sum / n;
      // The variance of the G images' mean: their spread over G (G - 1).
      const double variance = std::max(0.0, sumSquares - n * mean * mean) / (n * (n - 1));
      error[p] += variance / (mean * mean + 0.01) / 3;
    }
    if (!std::isfinite(error[p])) error[p] = 0;
  }
  // The box average, separable: along rows (a step of 1 between neighbours, `width` of them a
  // line), then along columns (a step of `width`, `height` of them a line).
  const auto boxPass = [&](const std::vector<double>& in, size_t step, int length) {
    std::vector<double> out(pixels, 0.0);
    for (size_t p = 0; p < pixels; ++p) {
      const int at = int(step == 1 ? p % size_t(width) : p / size_t(width));
      const int from = std::max(0, at - radius), to = std::min(length - 1, at + radius);
      double sum = 0;
      for (int k = from; k <= to; ++k) sum += in[p + (ptrdiff_t(k) - at) * ptrdiff_t(step)];
      out[p] = sum / double(to - from + 1);
    }
    return out;
  };
  const std::vector<double> smooth = boxPass(boxPass(error, 1, width), size_t(width), height);
  double mean = 0;
  for (double e : smooth) mean += e / double(pixels);
  const double least = mean > 0 ? floor * mean : 1;
  const int size = cellSizeFor(width, height, maxCells);
  const int cellsX = (width + size - 1) / size, cellsY = (height + size - 1) / size;
  std::vector<double> cellDensity(size_t(cellsX) * cellsY, 0.0);
  std::vector<int> cellPixels(cellDensity.size(), 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const size_t c = size_t(y / size) * cellsX + x / size;
      cellDensity[c] += std::sqrt(std::max(smooth[size_t(y) * width + x], least));
      ++cellPixels[c];
    }
  }
  double total = 0;
  for (size_t c = 0; c < cellDensity.size(); ++c) {
    cellDensity[c] /= cellPixels[c];
    total += cellDensity[c];
  }
  std::vector<float> density(cellDensity.size());
  for (size_t c = 0; c < density.size(); ++c)
    density[c] = float(cellDensity[c] * double(density.size()) / total);
  return PixelAllocation(width, height, size, std::move(density),
                         std::vector<uint8_t>(cellDensity.size(), bidirectional ? 1 : 0));
}

PixelAllocation::PixelAllocation(int width, int height, int cellSize, std::vector<float> density,
                                 std::vector<uint8_t> bidirectional)
    : width_(width), height_(height), cellSize_(cellSize) {
  if (width <= 0 || height <= 0 || width > kMaxSide || height > kMaxSide || cellSize <= 0 ||
      cellSize > kMaxSide) {
    throw std::invalid_argument("pixel allocation: film " + std::to_string(width) + "x" +
                                std::to_string(height) + " or cell size " +
                                std::to_string(cellSize) + " out of range");
  }
  cellsX_ = (width + cellSize - 1) / cellSize;
  cellsY_ = (height + cellSize - 1) / cellSize;
  const size_t cells = size_t(cellsX_) * cellsY_;
  if (cells > kMaxCells) {
    throw std::invalid_argument("pixel allocation: " + std::to_string(cells) +
                                " cells, more than " + std::to_string(kMaxCells) +
                                " (use larger cells)");
  }
  if (density.size() != cells || bidirectional.size() != cells) {
    throw std::invalid_argument("pixel allocation: " + std::to_string(cells) + " cells, but " +
                                std::to_string(density.size()) + " densities and " +
                                std::to_string(bidirectional.size()) + " estimators");
  }
  for (size_t c = 0; c < cells; ++c) {
    if (!std::isfinite(density[c]) || density[c] <= 0)
      throw std::invalid_argument("pixel allocation: cell " + std::to_string(c) + " has density " +
                                  std::to_string(density[c]) + " (must be finite and positive)");
    if (bidirectional[c] > 1)
      throw std::invalid_argument("pixel allocation: cell " + std::to_string(c) +
                                  " names estimator " + std::to_string(bidirectional[c]));
  }
  density_ = std::move(density);
  bidirectional_ = std::move(bidirectional);

  // P_c = d_c a_c / sum d a, on the grid of 2^-24 that Rng::nextFloat draws u0 from: cell c
  // is picked by the u0 in [cdf_{c-1}, cdf_c), exactly (cdf_c - cdf_{c-1}) 2^24 of the 2^24
  // values, and its weights (1) and 1 / F_B use that probability, not the unrounded one (which
  // would bias every sample of a cell by their ratio: 1% for a cell of a hundred grid points).
  // Every cell keeps one grid point at least (kMaxCells is far below 2^24).
  constexpr double kGrid = 16777216.0;  // 2^24
  std::vector<double> area(cells);
  double total = 0;
  for (int cy = 0; cy < cellsY_; ++cy) {
    for (int cx = 0; cx < cellsX_; ++cx) {
      const size_t c = size_t(cy) * cellsX_ + cx;
      area[c] = double(std::min(cellSize, width - cx * cellSize)) *
                std::min(cellSize, height - cy * cellSize);
      total += double(density_[c]) * area[c];
    }
  }
  std::vector<int64_t> grid(cells);
  double sum = 0;
  for (size_t c = 0; c < cells; ++c) {
    sum += double(density_[c]) * area[c];
    grid[c] = int64_t(std::llround(sum / total * kGrid));
  }
  const int64_t points = int64_t(kGrid);
  for (size_t c = 0; c < cells; ++c) {  // one point at least, and room left for the rest
    const int64_t least = (c == 0 ? 0 : grid[c - 1]) + 1;
    const int64_t most = points - int64_t(cells - 1 - c);
    grid[c] = std::clamp(grid[c], least, most);
  }
  grid.back() = points;
  cdf_.resize(cells);
  cameraWeight_.resize(cells);
  const double filmArea = double(width) * height;
  double bidirectionalShare = 0;
  concentration_ = 0;
  for (size_t c = 0; c < cells; ++c) {
    const double probability = double(grid[c] - (c == 0 ? 0 : grid[c - 1])) / kGrid;
    cdf_[c] = double(grid[c]) / kGrid;
    cameraWeight_[c] = float(area[c] / (filmArea * probability));
    if (bidirectional_[c]) bidirectionalShare += probability;
    // a_c / A of r_c^2, r_c = A P_c / a_c
    concentration_ += filmArea * probability * probability / area[c];
  }
  lightTracingWeight_ = bidirectionalShare > 0 ? 1 / bidirectionalShare : 0;
}

PixelAllocation::FilmSample PixelAllocation::sampleFilm(float u0, float u1, float u2) const {
  const size_t c =
      std::min(size_t(std::upper_bound(cdf_.begin(), cdf_.end(), double(u0)) - cdf_.begin()),
               cdf_.size() - 1);
  const int cx = int(c % cellsX_), cy = int(c / cellsX_);
  const int x0 = cx * cellSize_, y0 = cy * cellSize_;
  const int w = std::min(cellSize_, width_ - x0), h = std::min(cellSize_, height_ - y0);
  Vec2f film(float(x0) + u1 * float(w), float(y0) + u2 * float(h));
  // Rounding must not carry a point out of its cell (its weight is the cell's).
  film.x = std::min(film.x, std::nextafter(float(x0 + w), 0.0f));
  film.y = std::min(film.y, std::nextafter(float(y0 + h), 0.0f));
  return {film, cameraWeight_[c], bidirectional_[c] != 0};
}

int PixelAllocation::cellAt(const Vec2f& film) const {
  const int x = std::clamp(int(std::floor(film.x)), 0, width_ - 1);
  const int y = std::clamp(int(std::floor(film.y)), 0, height_ - 1);
  return (y / cellSize_) * cellsX_ + x / cellSize_;
}

bool PixelAllocation::bidirectionalAt(const Vec2f& film) const {
  return bidirectional_[size_t(cellAt(film))] != 0;
}

std::string PixelAllocation::encode() const {
  std::string s;
  appendBytes(s, kMagic);
  appendBytes(s, kVersion);
  appendBytes(s, int32_t(width_));
  appendBytes(s, int32_t(height_));
  appendBytes(s, int32_t(cellSize_));
  for (float d : density_) appendBytes(s, d);
  s.append(reinterpret_cast<const char*>(bidirectional_.data()), bidirectional_.size());
  return s;
}

PixelAllocation PixelAllocation::decode(const std::string& bytes) {
  size_t at = 0;
  uint32_t magic = 0, version = 0;
  int32_t width = 0, height = 0, cellSize = 0;
  if (!readBytes(bytes, at, &magic) || magic != kMagic || !readBytes(bytes, at, &version) ||
      version != kVersion || !readBytes(bytes, at, &width) || !readBytes(bytes, at, &height) ||
      !readBytes(bytes, at, &cellSize)) {
    throw std::invalid_argument("pixel allocation: not a pixel allocation of version 1");
  }
  if (width <= 0 || height <= 0 || width > kMaxSide || height > kMaxSide || cellSize <= 0 ||
      cellSize > kMaxSide) {
    throw std::invalid_argument("pixel allocation: film or cell size out of range");
  }
  const size_t cells =
      size_t((width + cellSize - 1) / cellSize) * size_t((height + cellSize - 1) / cellSize);
  if (cells > kMaxCells || bytes.size() - at != cells * (sizeof(float) + 1))
    throw std::invalid_argument("pixel allocation: " + std::to_string(bytes.size()) +
                                " bytes do not hold " + std::to_string(cells) + " cells");
  std::vector<float> density(cells);
  for (float& d : density) readBytes(bytes, at, &d);
  std::vector<uint8_t> bidirectional(bytes.begin() + std::ptrdiff_t(at), bytes.end());
  return PixelAllocation(width, height, cellSize, std::move(density), std::move(bidirectional));
}

}  // namespace farm
