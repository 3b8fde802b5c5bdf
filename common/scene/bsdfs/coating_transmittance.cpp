#include "common/scene/bsdfs/coating_transmittance.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <mutex>
#include <stdexcept>
#include <tuple>

#include "common/scene/bsdfs/fresnel.h"
#include "common/scene/bsdfs/microfacet.h"

namespace farm {

namespace {

// T(mu) by quadrature over the facets the rough dielectric samples for wo (the midpoints of an
// n x n grid of its two numbers): each facet refracts the share 1 - F(wo.m) of what it
// receives, and what is left of the refraction's f |cos| / pdf once D, the Fresnel choice and
// the Jacobians cancel is Microfacet::weight; in energy (importance) form, with no eta^2
// compression. So this is the mean weight of RoughDielectricBsdf's refractions in importance
// form, computed without it.
double coatTransmittance(const Microfacet& facets, float eta, float mu, int n) {
  if (mu <= 0) return 0;
  const Vec3f wo(std::sqrt(std::max(0.0f, 1 - mu * mu)), 0, mu);
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const Vec3f m = facets.sample(wo, (i + 0.5f) / n, (j + 0.5f) / n);
      const float woh = dot(wo, m);
      if (woh <= 0) continue;
      float cosT;
      const float f = fresnelDielectric(woh, eta, &cosT);
      if (f >= 1) continue;
      const Vec3f wi = refractedAbout(wo, m, eta, cosT);
      if (wi.z >= 0) continue;
      sum += (1 - f) * facets.weight(wo, wi, m);
    }
  }
  return sum / (double(n) * n);
}

constexpr int kCoatQuadrature = 32;  // facets per axis and table entry

}  // namespace

CoatingTransmittance::CoatingTransmittance(MicrofacetDistribution dist, float alpha, float eta) {
  if (!(alpha > 0) || !(eta > 0) || eta == 1 || !std::isfinite(alpha) || !std::isfinite(eta))
    throw std::invalid_argument("a coating needs alpha > 0 and a relative index > 0, != 1");
  const Microfacet facets{dist, alpha};
  outside_.resize(kResolution);
  double inside = 0;  // 2 \int T_in(mu) mu dmu by the trapezoid rule over the same mu
  for (int k = 0; k < kResolution; ++k) {
    const float mu = float(k) / (kResolution - 1);
    outside_[size_t(k)] = float(coatTransmittance(facets, eta, mu, kCoatQuadrature));
    const double weight = (k == 0 || k == kResolution - 1) ? 0.5 : 1.0;
    inside += weight * 2 * mu * coatTransmittance(facets, 1 / eta, mu, kCoatQuadrature);
  }
  inside /= (kResolution - 1);
  internalDiffuseReflectance_ = float(1 - inside);
}

std::shared_ptr<const CoatingTransmittance> sharedCoatingTransmittance(MicrofacetDistribution dist,
                                                                       float alpha, float eta) {
  static std::mutex mutex;
  static std::map<std::tuple<int, float, float>, std::weak_ptr<const CoatingTransmittance>> shared;
  const std::lock_guard<std::mutex> lock(mutex);
  const auto key = std::make_tuple(int(dist), alpha, eta);
  if (auto alive = shared[key].lock()) return alive;
  for (auto it = shared.begin(); it != shared.end();)  // forget the dead ones
    it = it->second.expired() ? shared.erase(it) : std::next(it);
  auto made = std::make_shared<const CoatingTransmittance>(dist, alpha, eta);
  shared[key] = made;
  return made;
}

float CoatingTransmittance::lookup(const std::vector<float>& table, float mu) {
  const float x = std::clamp(mu, 0.0f, 1.0f) * (kResolution - 1);
  const int k = std::min(int(x), kResolution - 2);
  const float t = x - float(k);
  return (1 - t) * table[size_t(k)] + t * table[size_t(k) + 1];
}

}  // namespace farm
