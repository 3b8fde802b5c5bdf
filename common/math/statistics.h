#pragma once
// Quantiles for the statistical tests of the samplers: the standard normal's (Acklam's
// rational approximation, relative error below 1.2e-9), Student's t's, and the chi-square
// distribution's
// (Wilson and Hilferty 1931: (X/k)^(1/3) is nearly normal; a few per cent from the exact
// quantile at k >= 10, on the safe side in the upper tail).
#include <algorithm>
#include <cmath>
#include <vector>

namespace farm {

// z with P(Z <= z) = p for a standard normal Z, 0 < p < 1.
inline double normalQuantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  const double low = 0.02425, high = 1 - low;
  if (p < low) {
    double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > high) return -normalQuantile(1 - p);
  double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

// t with P(T <= t) = p for Student's t with nu degrees of freedom: the Cornish-Fisher expansion
// about the normal quantile (Abramowitz and Stegun 26.7.5), within a per cent for nu >= 10.
inline double studentQuantile(double nu, double p) {
  const double z = normalQuantile(p), z2 = z * z;
  const double g1 = (z2 + 1) * z / 4;
  const double g2 = ((5 * z2 + 16) * z2 + 3) * z / 96;
  const double g3 = (((3 * z2 + 19) * z2 + 17) * z2 - 15) * z / 384;
  return z + g1 / nu + g2 / (nu * nu) + g3 / (nu * nu * nu);
}

// x with P(X > x) = alpha for X chi-square distributed with k degrees of freedom.
inline double chiSquareQuantile(double k, double alpha) {
  double z = normalQuantile(1 - alpha);
  double h = 2 / (9 * k);
  double t = 1 - h + z * std::sqrt(h);
  return k * t * t * t;
}

// The mean of independent, identically distributed estimates and its standard error: the
// sample standard deviation (n - 1 in the denominator) over sqrt(n). From the estimates' own
// spread, never from their distance to an expected value.
struct MeanEstimate {
  double mean = 0, standardError = 0;
};

inline MeanEstimate meanOfIndependent(const std::vector<double>& x) {
  MeanEstimate e;
  const double n = double(x.size());
  if (x.empty()) return e;
  double sum = 0;
  for (double v : x) sum += v;
  e.mean = sum / n;
  if (x.size() < 2) return e;
  double squares = 0;  // about the mean, not sum(x^2) - n mean^2: no cancellation
  for (double v : x) squares += (v - e.mean) * (v - e.mean);
  e.standardError = std::sqrt(squares / (n - 1) / n);
  return e;
}

}  // namespace farm
