#pragma once
// Where a job of independent samples puts its samples on the film, and which of the two
// independent estimators (path tracing or bidirectional path tracing) takes each part of the
// image (issue 42, part 4; docs/corpus.md, "Per-pixel estimators and sample density").
//
// The film is cut into cells of cellSize x cellSize pixels (clipped at the right and bottom
// edges). Cell c has a relative density d_c and an estimator. A sample picks cell c with
// probability P_c = d_c a_c / sum_c' d_c' a_c' (a_c its area in pixels) and a film point uniform
// in it, so its film point has density P_c / a_c against 1 / A for the uniform film (A the film's
// area): the camera-side contributions of a sample in cell c are weighted by
//     a_c / (A P_c) = (sum_c' d_c' a_c') / (A d_c)                                       (1)
// to stay unbiased for any density. The estimator of every pixel is the one of its cell, weights
// 0 or 1 by pixel, which sum to one: the image stays unbiased whatever the cells say (a partition
// of the film is the simplest multiple-importance weighting of two estimators; Veach 1997, 9.2).
// Light tracing's splats (bidirectional strategies with one camera vertex, t = 1) land anywhere:
// only the bidirectional cells' samples trace light subpaths, a share F_B = sum_{c in B} P_c of
// all samples, so such a splat counts 1 / F_B times, and only where it lands in a bidirectional
// cell (a path-traced pixel has its whole estimate from path tracing already).
#include <cstdint>
#include <string>
#include <vector>

#include "common/film/image.h"
#include "common/math/vec.h"

namespace farm {

class PixelAllocation {
 public:
  // Throws std::invalid_argument unless the cells cover the film exactly, every density is
  // finite and positive, and a cell with bidirectional samples gets some.
  PixelAllocation(int width, int height, int cellSize, std::vector<float> density,
                  std::vector<uint8_t> bidirectional);

  int width() const { return width_; }
  int height() const { return height_; }
  int cellSize() const { return cellSize_; }
  int cellsX() const { return cellsX_; }
  int cellsY() const { return cellsY_; }
  const std::vector<float>& density() const { return density_; }
  const std::vector<uint8_t>& bidirectional() const { return bidirectional_; }

  // The cell size that keeps a film of width x height within maxCells cells.
  static int cellSizeFor(int width, int height, int maxCells);

  // One estimator everywhere (bidirectional or not), its samples where a pilot saw its error:
  // from G >= 2 independent images of the pilot (its chain groups), each pixel's relative error
  // e_p (the variance of their mean over (m^2 + 0.01), m that mean, the channels averaged: the
  // relative MSE's terms, common/film/error_metrics.h) averaged over a (2 radius + 1)^2 box
  // (one pixel's spread over G images is mostly noise), floored at `floor` times its mean over
  // the film (no pixel starves on the pilot's word), and the density n_p ~ sqrt(e_p): the one
  // that minimizes the mean of e_p n_pilot / n_p for a fixed total of samples of equal cost
  // (Lagrange). Cells of cellSizeFor(width, height, maxCells) take their pixels' mean density.
  // The job's image stays unbiased whatever the pilot saw; the pilot's samples must come from
  // other random numbers than the job's (its densities would follow the job's own noise).
  static PixelAllocation byError(const std::vector<Image>& groups, bool bidirectional,
                                 int radius = 2, double floor = 0.01, int maxCells = 4096);

  struct FilmSample {
    Vec2f film;          // pixels
    float cameraWeight;  // (1): the weight of this sample's camera-side contributions
    bool bidirectional;  // the cell's estimator
  };
  // A film point from three uniform numbers in [0, 1); u0, which picks the cell, on the grid
  // of 2^-24 (Rng::nextFloat's), for which the weights are exact.
  FilmSample sampleFilm(float u0, float u1, float u2) const;

  // The film's mean of r^2, r a pixel's density over the uniform film's (A P_c / a_c): by how
  // much the allocation lowers the relative MSE of uniform sampling, sum e / sum (e / r), where
  // each pixel's error per sample e goes as r^2 (byError's n_p ~ sqrt(e_p)). 1 when uniform.
  double concentration() const { return concentration_; }

  // 1 / F_B: the weight of a light-tracing splat that lands in a bidirectional cell (0 when
  // no cell is bidirectional).
  double lightTracingWeight() const { return lightTracingWeight_; }
  bool bidirectionalAt(const Vec2f& film) const;

  // The byte form that travels in a work unit (little-endian, as the chains' states).
  std::string encode() const;
  // Throws std::invalid_argument on a malformed or inconsistent form.
  static PixelAllocation decode(const std::string& bytes);

 private:
  int cellAt(const Vec2f& film) const;

  int width_, height_, cellSize_, cellsX_, cellsY_;
  std::vector<float> density_;
  std::vector<uint8_t> bidirectional_;
  std::vector<double> cdf_;  // P_c summed over cells 0..c, cdf_.back() == 1
  std::vector<float> cameraWeight_;
  double lightTracingWeight_ = 0;
  double concentration_ = 1;
};

}  // namespace farm
