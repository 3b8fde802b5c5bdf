#pragma once
// The mean of an image's values around each pixel without the pixel itself: a stand-in for the
// pixel's true value that holds none of the pixel's own noise, for error estimates that divide
// by it (batch_means.h, cross_estimate.h).
#include <vector>

namespace farm {

// values: 3 channels a pixel, row-major, width x height. Per channel, the mean over each pixel's
// window x window neighbourhood (window odd), clipped at the image's border, without the pixel
// itself; by summed-area tables.
std::vector<double> neighbourMean(const std::vector<double>& values, int width, int height,
                                  int window);

}  // namespace farm
