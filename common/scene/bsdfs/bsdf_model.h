#pragma once
// What every BSDF model (this folder, one class per model) offers the Bsdf that holds it
// (common/scene/bsdf.h), in the local shading frame (z = normal). Directions point away from
// the surface: wo towards the previous vertex of the path being built, wi the sampled (or
// connected) next one.
//
//   static constexpr bool kDelta;   only Dirac lobes (then eval and pdf are zero)
//   explicit Model(const BsdfDescription&);
//   Spectrum eval(wo, wi, TransportMode) const;   f(wo, wi) without the cosine
//   float pdf(wo, wi) const;                       solid-angle density of sample()
//   bool sample(wo, const float u[3], TransportMode, BsdfSample*) const;
//   bool isBlack() const;                          reflects nothing at all
//   void setReflectance(const Spectrum&);          where a texture gives the diffuse reflectance
//                                                  (models without one ignore it)
// and where kDelta, the Dirac lobes the path-space mutations evaluate paths through (Veach 1997,
// 8.3.2), as Bsdf documents them: specularDirection, specularLobe, diracJacobian.
//
// A two-sided model is called with wo on its front (z > 0): Bsdf mirrors both directions
// of a back-side query, and the sampled direction back.
#include "common/math/vec.h"

namespace farm {

// Which quantity a path carries: the BSDF is not symmetric under refraction (Veach 1997, 5.2).
enum class TransportMode { Radiance, Importance };

struct BsdfSample {
  Vec3f wi;
  Spectrum weight;     // f(wo, wi) |cos(wi)| / pdf
  float pdf = 0;       // solid-angle density (for a delta lobe: the discrete probability)
  bool delta = false;  // sampled from a Dirac lobe: cannot be evaluated or connected to
};

}  // namespace farm
