#pragma once
// Error of a render against a reference, with the definitions of ../shared/tools/imgcmp.py:
// relMSE = mean over pixels and channels of (x - r)^2 / (r^2 + 0.01); channel means over pixels
// capped at the reference's 99.9th percentile (a tiny visible light would decide the mean alone).
#include <string>

#include "common/film/image.h"

namespace farm {

struct ErrorMetrics {
  double rmse = 0;
  double relMse = 0;
  double mean[3] = {0, 0, 0};           // of the image, capped
  double referenceMean[3] = {0, 0, 0};  // of the reference, capped
  double meanDeviation[3] = {0, 0, 0};  // |mean - ref| / ref per channel
  long nonFinite = 0, negative = 0;     // counts of channel values
};

// The value channel means are capped at: the reference's 99.9th percentile over all channel
// values (numpy.percentile's, as imgcmp.py takes it), at least 1e-6; NaN when the reference holds
// a NaN.
double meanCap(const Image& reference);

// Returns false (and sets *error) when the sizes differ.
bool compareImages(const Image& image, const Image& reference, ErrorMetrics* out,
                   std::string* error);

}  // namespace farm
