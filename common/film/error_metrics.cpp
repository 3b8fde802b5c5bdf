#include "common/film/error_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace farm {

namespace {

// numpy.percentile(values, q) with its default "linear" method, step for step (virtual index and
// the two-sided lerp), so that the cap agrees with imgcmp.py to the last bit in ordinary cases.
double numpyPercentile(std::vector<double> values, double q) {
  const size_t n = values.size();
  for (double v : values)
    if (std::isnan(v)) return std::numeric_limits<double>::quiet_NaN();  // numpy propagates NaN
  const double quantile = q / 100.0;
  // numpy's "linear" method: get_virtual_index = (n - 1) * quantile.
  const double virtualIndex = double(n - 1) * quantile;
  double previous = std::floor(virtualIndex);
  double gamma = virtualIndex - previous;
  size_t lo = size_t(std::clamp(previous, 0.0, double(n - 1)));
  size_t hi = std::min(lo + 1, n - 1);
  if (virtualIndex >= double(n - 1)) lo = hi = n - 1;
  std::nth_element(values.begin(), values.begin() + long(lo), values.end());
  const double a = values[lo];
  const double b = hi == lo ? a : *std::min_element(values.begin() + long(lo) + 1, values.end());
  const double diff = b - a;
  // numpy's _lerp: a + diff * t, or b - diff * (1 - t) for t >= 0.5 (exact at both ends).
  return gamma >= 0.5 ? b - diff * (1.0 - gamma) : a + diff * gamma;
}

// np.minimum propagates NaN from either side.
double capped(double v, double cap) {
  if (std::isnan(v) || std::isnan(cap)) return std::numeric_limits<double>::quiet_NaN();
  return std::min(v, cap);
}

}  // namespace

double meanCap(const Image& reference) {
  // A tiny directly visible light (a few pixels of 1e4) would otherwise decide the means alone.
  const double percentile =
      numpyPercentile(std::vector<double>(reference.rgb.begin(), reference.rgb.end()), 99.9);
  // Python's max(p, 1e-6) returns p when p is NaN (NaN > 1e-6 is false), and so do we.
  return std::isnan(percentile) ? percentile : std::max(percentile, 1e-6);
}

bool compareImages(const Image& image, const Image& reference, ErrorMetrics* out,
                   std::string* error) {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return false;
  };
  if (image.width != reference.width || image.height != reference.height)
    return fail("size differs: " + std::to_string(image.width) + "x" +
                std::to_string(image.height) + " vs reference " + std::to_string(reference.width) +
                "x" + std::to_string(reference.height));
  const size_t count = size_t(image.width) * size_t(image.height) * 3;
  if (image.rgb.size() != count || reference.rgb.size() != count)
    return fail("image buffer does not match its size");
  if (count == 0) return fail("empty images");

  ErrorMetrics m;
  const double cap = meanCap(reference);

  double sumMean[3] = {0, 0, 0}, sumRefMean[3] = {0, 0, 0};
  double sumSq = 0, sumRel = 0;
  for (size_t i = 0; i < count; ++i) {
    const double x = image.rgb[i], r = reference.rgb[i];
    const int c = int(i % 3);
    sumMean[c] += capped(x, cap);
    sumRefMean[c] += capped(r, cap);
    const double d2 = (x - r) * (x - r);
    sumSq += d2;
    sumRel += d2 / (r * r + 1e-2);
    if (!std::isfinite(x)) ++m.nonFinite;
    if (x < 0) ++m.negative;
  }
  const double pixels = double(count / 3);
  for (int c = 0; c < 3; ++c) {
    m.mean[c] = sumMean[c] / pixels;
    m.referenceMean[c] = sumRefMean[c] / pixels;
    m.meanDeviation[c] =
        std::fabs(m.mean[c] - m.referenceMean[c]) / std::max(m.referenceMean[c], 1e-12);
  }
  m.rmse = std::sqrt(sumSq / double(count));
  m.relMse = sumRel / double(count);
  if (out) *out = m;
  return true;
}

}  // namespace farm
