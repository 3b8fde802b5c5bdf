#include "common/scene/medium.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace farm {

namespace {

float henyeyGreenstein(float cosTheta, float g) {
  const float denom = 1 + g * g - 2 * g * cosTheta;
  return (1 - g * g) / (4 * kPi * denom * std::sqrt(std::max(denom, 0.0f)));
}

Spectrum expSpectrum(const Spectrum& s) {
  return {std::exp(s.x), std::exp(s.y), std::exp(s.z)};
}

bool grey(const Spectrum& s) {
  return s.x == s.y && s.y == s.z;
}

// Transmittance of a homogeneous segment; an infinite one passes only what does not go out.
Spectrum homogeneousTransmittance(const Spectrum& sigmaT, float t) {
  if (grey(sigmaT)) return Spectrum(sigmaT.x > 0 ? std::exp(-sigmaT.x * t) : 1.0f);
  Spectrum T;
  for (int c = 0; c < 3; ++c) T[c] = sigmaT[c] > 0 ? std::exp(-sigmaT[c] * t) : 1.0f;
  return T;
}

bool finiteNonNegative(const Spectrum& s) {
  for (int c = 0; c < 3; ++c)
    if (!(s[c] >= 0) || !std::isfinite(s[c])) return false;
  return true;
}

// Russian roulette on a ratio-tracking estimate once it is small: unbiased, and bounds the work
// in optically thick grids (pbrt-v4 does the same).
constexpr float kRatioTrackingRoulette = 0.1f;

}  // namespace

float HenyeyGreenstein::eval(const Vec3f& wo, const Vec3f& wi) const {
  return henyeyGreenstein(-dot(wo, wi), g_);
}

Vec3f HenyeyGreenstein::sample(const Vec3f& wo, const Vec2f& u, float* pdf) const {
  // Light arrives along -wi and leaves along wo, so the phase function's cosine is that between
  // wi and -wo (the direction a camera path would go on in): wi is sampled about -wo, by
  // inverting the cosine's distribution (pbrt-v3, section 15.2.3).
  float cosTheta;
  if (std::fabs(g_) < 1e-3f) {
    cosTheta = 1 - 2 * u.x;
  } else {
    const float s = (1 - g_ * g_) / (1 - g_ + 2 * g_ * u.x);
    cosTheta = (1 + g_ * g_ - s * s) / (2 * g_);
  }
  cosTheta = std::clamp(cosTheta, -1.0f, 1.0f);
  const float sinTheta = std::sqrt(std::max(0.0f, 1 - cosTheta * cosTheta));
  const float phi = 2 * kPi * u.y;
  const Frame frame(-wo);
  const Vec3f wi =
      frame.toWorld(Vec3f(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta));
  *pdf = henyeyGreenstein(cosTheta, g_);
  return wi;
}

Medium::Medium(const MediumDescription& desc) : desc_(desc), sigmaT_(desc.sigmaA + desc.sigmaS) {
  if (desc_.type == MediumDescription::Type::Grid) {
    float largest = 0;
    for (float v : desc_.density) largest = std::max(largest, v);
    majorant_ = largest * sigmaT_.x;
  }
}

float Medium::value(int x, int y, int z) const {
  if (x < 0 || y < 0 || z < 0 || x >= desc_.nx || y >= desc_.ny || z >= desc_.nz) return 0;
  return desc_.density[(size_t(z) * size_t(desc_.ny) + size_t(y)) * size_t(desc_.nx) + size_t(x)];
}

float Medium::density(const Vec3f& p) const {
  if (isHomogeneous()) return 1;
  const Vec3f q = desc_.worldToGrid.applyPoint(p);
  if (!(q.x >= 0 && q.y >= 0 && q.z >= 0 && q.x <= 1 && q.y <= 1 && q.z <= 1)) return 0;
  // Continuous grid coordinates whose integer points are the samples.
  float g[3];
  const int n[3] = {desc_.nx, desc_.ny, desc_.nz};
  for (int a = 0; a < 3; ++a)
    g[a] = desc_.cellCentred ? q[a] * float(n[a]) - 0.5f : q[a] * float(std::max(n[a] - 1, 0));
  const int x = int(std::floor(g[0])), y = int(std::floor(g[1])), z = int(std::floor(g[2]));
  const float fx = g[0] - float(x), fy = g[1] - float(y), fz = g[2] - float(z);
  auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
  const float c00 = lerp(value(x, y, z), value(x + 1, y, z), fx);
  const float c10 = lerp(value(x, y + 1, z), value(x + 1, y + 1, z), fx);
  const float c01 = lerp(value(x, y, z + 1), value(x + 1, y, z + 1), fx);
  const float c11 = lerp(value(x, y + 1, z + 1), value(x + 1, y + 1, z + 1), fx);
  return lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz);
}

bool Medium::clipToGrid(const Vec3f& o, const Vec3f& d, float tMax, float* t0, float* t1) const {
  // The grid's space is an affine image of the world's: a ray's parameter is the same in both.
  const Vec3f og = desc_.worldToGrid.applyPoint(o);
  const Vec3f dg = desc_.worldToGrid.applyVector(d);
  float lo = 0, hi = tMax;
  for (int a = 0; a < 3; ++a) {
    if (dg[a] == 0) {
      if (og[a] < 0 || og[a] > 1) return false;
      continue;
    }
    float ta = (0 - og[a]) / dg[a], tb = (1 - og[a]) / dg[a];
    if (ta > tb) std::swap(ta, tb);
    lo = std::max(lo, ta);
    hi = std::min(hi, tb);
  }
  *t0 = lo;
  *t1 = hi;
  return lo < hi;
}

MediumInteraction Medium::sampleInteraction(const Vec3f& o, const Vec3f& d, float tMax,
                                            Sampler& sampler, SampleStream stream) const {
  MediumInteraction out;
  if (isHomogeneous()) {
    // One channel's exponential, picked uniformly; the density of the distance is the mixture
    // of the three (one-sample MIS over channels, the balance heuristic).
    const float uChannel = sampler.next(stream), uDistance = sampler.next(stream);
    const int c = std::min(int(uChannel * 3), 2);
    // t = -log(1 - u) / sigma >= u / sigma: with u >= sigma tMax the flight passes the segment,
    // known without the logarithm (in thin media nearly every flight; in farm_plan_bench the
    // logarithm alone took 6% of pt's time in a medium of extinction 1e-6).
    const bool passes = !(sigmaT_[c] > 0) || uDistance >= sigmaT_[c] * tMax;
    const float t = passes ? kInfinity : -std::log1p(-uDistance) / sigmaT_[c];
    if (t < tMax) {
      const Spectrum T = homogeneousTransmittance(sigmaT_, t);
      const Spectrum density = sigmaT_ * T;
      const float pdf = (density.x + density.y + density.z) / 3;
      out.scattered = true;
      out.t = t;
      out.weight = pdf > 0 ? desc_.sigmaS * T / pdf : Spectrum(0.0f);
      return out;
    }
    // The probability of passing the segment is the channels' mean transmittance; in a grey
    // medium the weight, T over it, is 1.
    if (grey(sigmaT_)) return out;
    const Spectrum T = homogeneousTransmittance(sigmaT_, tMax);
    const float pdf = (T.x + T.y + T.z) / 3;
    out.weight = pdf > 0 ? T / pdf : Spectrum(0.0f);
    return out;
  }
  // Delta tracking (Woodcock et al. 1965): tentative collisions at the majorant's rate, each
  // real with probability sigma_t(x) / majorant; a real one scatters with weight the albedo.
  float t0, t1;
  if (majorant_ <= 0 || !clipToGrid(o, d, tMax, &t0, &t1)) return out;
  const float sigmaT = sigmaT_.x;
  float t = t0;
  for (;;) {
    t -= std::log1p(-sampler.next(stream)) / majorant_;
    const float uReal = sampler.next(stream);
    if (!(t < t1)) return out;
    if (uReal * majorant_ < density(o + d * t) * sigmaT) {
      out.scattered = true;
      out.t = t;
      out.weight = desc_.sigmaS / sigmaT;
      return out;
    }
  }
}

Spectrum Medium::transmittance(const Vec3f& o, const Vec3f& d, float tMax, Sampler& sampler,
                               SampleStream stream) const {
  if (isHomogeneous()) return homogeneousTransmittance(sigmaT_, tMax);
  // Ratio tracking (Cramer 1978; Novak et al. 2014): the product over tentative collisions of
  // the chance that each is null.
  float t0, t1;
  if (majorant_ <= 0 || !clipToGrid(o, d, tMax, &t0, &t1)) return Spectrum(1.0f);
  const float sigmaT = sigmaT_.x;
  float T = 1, t = t0;
  for (;;) {
    t -= std::log1p(-sampler.next(stream)) / majorant_;
    if (!(t < t1)) break;
    T *= 1 - density(o + d * t) * sigmaT / majorant_;
    if (T < kRatioTrackingRoulette) {
      if (sampler.next(stream) >= 0.5f) return Spectrum(0.0f);
      T *= 2;
    }
  }
  return Spectrum(T);
}

Spectrum Medium::marchedTransmittance(const Vec3f& o, const Vec3f& d, float tMax, int steps) const {
  if (isHomogeneous()) return homogeneousTransmittance(sigmaT_, tMax);
  float t0, t1;
  if (majorant_ <= 0 || !clipToGrid(o, d, tMax, &t0, &t1)) return Spectrum(1.0f);
  // The midpoint rule on the optical depth, in double.
  const int n = std::max(steps, 1);
  const double dt = (double(t1) - t0) / n;
  double depth = 0;
  for (int i = 0; i < n; ++i) depth += density(o + d * float(t0 + (i + 0.5) * dt));
  return expSpectrum(Spectrum(-float(depth * dt) * sigmaT_.x));
}

bool Medium::freeFlightChord(const Vec3f& o, const Vec3f& d, FreeFlightChord* chord) const {
  float t0, t1;
  if (!clipToGrid(o, d, kInfinity, &t0, &t1)) return false;
  // Steps of about half a cell: the chord's length in cells of the grid's finest axis.
  const Vec3f dg = desc_.worldToGrid.applyVector(d);
  const double cells =
      double(length(dg)) * (double(t1) - t0) * std::max({desc_.nx, desc_.ny, desc_.nz});
  chord->t0 = t0;
  chord->steps = int(std::min(std::max(std::ceil(2 * cells), 8.0), 4096.0));
  chord->dt = (double(t1) - t0) / chord->steps;
  return chord->dt > 0;
}

double Medium::chordSigma(const Vec3f& o, const Vec3f& d, const FreeFlightChord& c, int i) const {
  return double(sigmaT_.x) * density(o + d * float(c.t0 + (i + 0.5) * c.dt));
}

float Medium::sampleFreeFlight(const Vec3f& o, const Vec3f& d, float tMax, float uChannel,
                               float uDistance) const {
  if (isHomogeneous()) {
    const float sigma = sigmaT_[std::min(int(uChannel * 3), 2)];
    const double t = sigma > 0 ? -std::log1p(-double(uDistance)) / sigma : double(kInfinity);
    return t < tMax ? float(t) : tMax;
  }
  FreeFlightChord c;
  if (!freeFlightChord(o, d, &c)) return tMax;
  // Inverts the stepped optical depth at -log(1 - u).
  const double target = -std::log1p(-double(uDistance));
  double depth = 0;
  for (int i = 0; i < c.steps; ++i) {
    const double a = c.t0 + i * c.dt;
    if (!(a < tMax)) break;
    const double b = std::min(a + c.dt, double(tMax));
    const double sigma = chordSigma(o, d, c, i);
    if (depth + sigma * (b - a) >= target && sigma > 0) {
      const double t = a + (target - depth) / sigma;
      return t < tMax ? float(t) : tMax;
    }
    depth += sigma * (b - a);
  }
  return tMax;
}

double Medium::freeFlightDensity(const Vec3f& o, const Vec3f& d, float tMax, bool lands) const {
  if (isHomogeneous()) {
    double sum = 0;
    for (int c = 0; c < 3; ++c) {
      const double pass = std::exp(-double(sigmaT_[c]) * tMax);
      sum += lands ? double(sigmaT_[c]) * pass : pass;
    }
    return sum / 3;
  }
  FreeFlightChord c;
  if (!freeFlightChord(o, d, &c)) return lands ? 0.0 : 1.0;
  double depth = 0, sigmaAtEnd = 0;
  for (int i = 0; i < c.steps; ++i) {
    const double a = c.t0 + i * c.dt;
    if (!(a < tMax)) break;
    const double b = std::min(a + c.dt, double(tMax));
    const double sigma = chordSigma(o, d, c, i);
    depth += sigma * (b - a);
    sigmaAtEnd = b == double(tMax) ? sigma : 0.0;
  }
  return lands ? sigmaAtEnd * std::exp(-depth) : std::exp(-depth);
}

std::string mediumProblem(const MediumDescription& desc) {
  if (!finiteNonNegative(desc.sigmaA) || !finiteNonNegative(desc.sigmaS))
    return "sigma_a and sigma_s must be finite and >= 0";
  if (!(std::fabs(desc.g) < 1)) return "the phase function's g must lie in (-1, 1)";
  if (desc.type == MediumDescription::Type::Homogeneous) return "";
  if (desc.nx < 1 || desc.ny < 1 || desc.nz < 1)
    return "a density grid needs at least one value along each axis";
  if (size_t(desc.nx) * size_t(desc.ny) * size_t(desc.nz) != desc.density.size())
    return "the density grid has " + std::to_string(desc.density.size()) + " values, not " +
           std::to_string(desc.nx) + " x " + std::to_string(desc.ny) + " x " +
           std::to_string(desc.nz);
  for (float v : desc.density)
    if (!(v >= 0) || !std::isfinite(v)) return "densities must be finite and >= 0";
  const Spectrum sigmaT = desc.sigmaA + desc.sigmaS;
  if (sigmaT.x != sigmaT.y || sigmaT.x != sigmaT.z)
    return "a density grid's sigma_t (sigma_a + sigma_s) must be the same in every channel (its "
           "albedo may have colour)";
  if (!desc.worldToGrid.isFinite()) return "the grid's transform is not finite";
  return "";
}

}  // namespace farm
