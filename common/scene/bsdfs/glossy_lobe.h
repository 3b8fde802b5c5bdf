#pragma once
// What pbrt-v3's plastic and Mitsuba's roughplastic (PlasticBsdf, CoatedDiffuseBsdf) share: a
// Torrance-Sparrow reflection lobe whose Fresnel term is a dielectric's (the coat's), beside a
// diffuse lobe; each lobe sampled with a probability, the density the mixture's (the
// one-sample model of Veach 1997, 9.2.4), so that eval cos / pdf is the sample's weight.
#include "common/sampling/warp.h"
#include "common/scene/bsdfs/bsdf_model.h"
#include "common/scene/bsdfs/microfacet.h"
#include "common/scene/scene_description.h"

namespace farm {

class GlossyLobe {
 public:
  explicit GlossyLobe(const BsdfDescription& desc)
      : facets_{desc.distribution, desc.alpha},
        eta_(desc.intIOR / desc.extIOR),
        specularReflectance_(desc.specularReflectance) {}
  // The lobe's value (zero below the surface).
  Spectrum eval(const Vec3f& wo, const Vec3f& wi) const;
  // Draws a facet facing wo and reflects wo in it; false when the facet faces away.
  bool sample(const Vec3f& wo, float u1, float u2, Vec3f* wi) const;
  const Spectrum& specularReflectance() const { return specularReflectance_; }
  const Microfacet& facets() const { return facets_; }

 private:
  Microfacet facets_;
  float eta_;  // the coat's index over the outside's
  Spectrum specularReflectance_;
};

// The density of the mixture that takes the diffuse lobe with probability diffuseProbability.
float diffuseOrGlossyPdf(float diffuseProbability, const GlossyLobe& glossy, const Vec3f& wo,
                         const Vec3f& wi);

// A sample of the mixture of `model` (whose pdf and eval are the mixture's), from wo on the
// front side.
template <class Model>
bool sampleDiffuseOrGlossy(const Model& model, float diffuseProbability, const GlossyLobe& glossy,
                           const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) {
  if (wo.z <= 0) return false;
  Vec3f wi;
  if (u[0] < diffuseProbability) {
    wi = squareToCosineHemisphere({u[1], u[2]});
  } else if (!glossy.sample(wo, u[1], u[2], &wi)) {
    return false;
  }
  if (wi.z <= 0) return false;
  const float pdf = model.pdf(wo, wi);
  if (!(pdf > 0)) return false;
  out->wi = wi;
  out->pdf = pdf;
  out->weight = model.eval(wo, wi, mode) * (wi.z / pdf);
  out->delta = false;
  return isValidRadiance(out->weight);
}

}  // namespace farm
