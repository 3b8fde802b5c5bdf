#pragma once
// The share of the power arriving at a rough dielectric boundary from a direction of cosine mu
// (on either side) that it transmits, T(mu), as Mitsuba's roughplastic uses it (its
// RoughTransmittance): the directional albedo of the boundary's transmission lobe, for one
// distribution, roughness and relative index. Tabulated at construction by a quadrature over
// the microfacet normals the rough dielectric samples; looked up linearly in mu.
#include <memory>
#include <vector>

#include "common/scene/scene_description.h"

namespace farm {

class CoatingTransmittance {
 public:
  // eta: the index of the coat over that of the outside (> 0, != 1).
  CoatingTransmittance(MicrofacetDistribution dist, float alpha, float eta);
  // T(mu) for light arriving from outside, mu in [0, 1].
  float fromOutside(float mu) const { return lookup(outside_, mu); }
  // The share of diffuse light inside the coat that it reflects back in: 1 - 2 \int T_in(mu) mu
  // dmu, with T_in the transmittance from inside (Mitsuba's Fdr).
  float internalDiffuseReflectance() const { return internalDiffuseReflectance_; }

  static constexpr int kResolution = 64;  // table entries over mu in [0, 1]

 private:
  static float lookup(const std::vector<float>& table, float mu);
  std::vector<float> outside_;
  float internalDiffuseReflectance_ = 0;
};

// The coating for these parameters, shared by every description alive that asked for the same
// ones (a scene's many plastics of one kind tabulate it once); freed with the last of them.
std::shared_ptr<const CoatingTransmittance> sharedCoatingTransmittance(MicrofacetDistribution dist,
                                                                       float alpha, float eta);

}  // namespace farm
