#pragma once
// The error of an image estimated without a reference, by batch means: the chains of a job fall
// into G independent groups (ChainSpec::errorGroup), each group's image is an unbiased estimate
// of the whole on its own, and the spread between them estimates the variance of their
// work-weighted mean, the image the job shows. With W_g units of work in group g (W in all) and
// variance s^2 / W_g for group g's image, sum_g W_g (x_g - x)^2 has expectation (G - 1) s^2, so
//
//   Var(x) = s^2 / W  ~  sum_g W_g (x_g - x)^2 / ((G - 1) W)
//
// per channel value. A normalization constant Z that scales every group alike (the bootstrap's)
// moves them together, out of the spread's sight: its relative variance adds x^2 Var(Z)/Z^2.
// The relative MSE is then estimated as common/film/error_metrics.h measures it against a
// reference, mean of Var(x) / (r^2 + 0.01), with r^2 estimated without the reference: products
// of different groups' values (E[x_g x_h] = r^2 for g != h), averaged over the pixel's
// neighbours without the pixel itself (batch_means.cpp says why: a pixel alone cannot tell its
// firefly from its rare bright samples). Measured against the references at 2-6 s a render
// (every algorithm; cornell-box, veach-bidir, veach-mis, veach-ajar; seed 11): 0.72-1.32 of the
// reference's relative MSE, where the groups' median gave 0.28-23 (veach-ajar and veach-mis
// at few samples a pixel) and the image itself 0.3-1. Its limit: light that one group alone
// has found over a patch wider than the window. A firefly blob over darkness (erpt with two
// groups: r^2 estimated as blob x background, far above the truth) and a bright patch only one
// group's chains reached (r^2 estimated near 0) look alike to it; at seeds 12 and 13, 4 of 42
// such renders fell outside a factor of two (0.04, 0.23, 0.30 and 14). The numerator was right
// in each: with the reference's r^2 in the denominator, 0.92-1.20 of the measured error.
// What the spread cannot see: bias (an algorithm that misses light misses it in every group)
// and light no group has found yet: on water-caustic, where every local sampler misses a third
// of the light, it sees the noise and not the deficit.
#include <cstddef>
#include <string>
#include <vector>

#include "common/film/image.h"

namespace farm {

struct ErrorEstimate {
  double relMse = 0;
  double rmse = 0;
};

// The images an estimate reads, a band of rows at a time: the estimate holds a band of each
// (and the window's rows above and below it), never the whole of them, so that a coordinator
// resolves them from its films as it goes (at 3840x2160 with four groups, whole images and
// their per-value products took 1.2 GB).
class ErrorFilms {
 public:
  virtual ~ErrorFilms() = default;
  virtual int width() const = 0;
  virtual int height() const = 0;
  virtual size_t groups() const = 0;
  // Rows [y0, y1) of group g's image (g < groups()) or, for g == groups(), of the image (their
  // work-weighted mean): 3 floats a pixel, row-major, from the top row, into out.
  virtual void rows(size_t g, int y0, int y1, float* out) const = 0;
};

// Whole images as ErrorFilms: rows copied out of them (the images outlive it).
class ImageFilms : public ErrorFilms {
 public:
  ImageFilms(const std::vector<Image>& groups, const Image& image)
      : groups_(groups), image_(image) {}
  int width() const override { return image_.width; }
  int height() const override { return image_.height; }
  size_t groups() const override { return groups_.size(); }
  void rows(size_t g, int y0, int y1, float* out) const override;

 private:
  const std::vector<Image>& groups_;
  const Image& image_;
};

// work: the groups' work (> 0 each); zRelativeVariance: Var(Z) / Z^2 of a shared normalization
// (0: none). False with *error for fewer than two groups, an empty film or no work. bandRows:
// the rows read at a time (the estimate does not depend on it beyond rounding).
bool estimateError(const ErrorFilms& films, const std::vector<double>& work,
                   double zRelativeVariance, ErrorEstimate* out, std::string* error,
                   int bandRows = 64);

// The same from whole images. groups: the groups' images (G >= 2, each of image's size);
// image: their work-weighted mean. False with *error also for sizes that differ.
bool estimateError(const std::vector<Image>& groups, const std::vector<double>& work,
                   const Image& image, double zRelativeVariance, ErrorEstimate* out,
                   std::string* error, int bandRows = 64);

}  // namespace farm
