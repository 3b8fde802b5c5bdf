#pragma once
// Manifold next-event estimation (Hanika, Droske and Fascione 2015) made unbiased by specular
// manifold sampling's weight (Zeltner, Georgiev and Jakob 2020), for the bootstrap of
// path-space MLT: what reaches a diffuse surface from a light through specular interfaces
// (L S+ D ..., the floor under water lit through its surface, the water's caustics) is a set of
// measure zero for BDPT's connections and needs its camera paths to hit the light, which a small
// light makes rare: BDPT's candidates then miss that light, and so do Z and the seeds.
//
// One sample traces a camera subpath (a uniform film point, then BSDF sampling; where the depth
// is unbounded, Russian roulette past a few edges, as in BDPT) and at each non-specular vertex z
// picks a light point y; a seed point on a specular surface (near where the segment from z to y
// crosses one, or anywhere on them), a ray from y through it, specular bounces (each lobe drawn by
// its Fresnel share) until the ray meets a non-specular surface, and a manifold walk
// (manifold_walk.h) of that end to z give a specular chain joining them: a path y S+ z .. E. The
// walk is deterministic, but which of the chains joining y and z it finds depends on the seed, with
// some probability P; the number of further seeds drawn until the same chain is found again is
// geometric with mean 1 / P, an unbiased estimate of it. So the path's value f / p is
//   f(x) / (ratio(x) p_light(y) p_camera(z .. E)) * K,
// with ratio the specular chain's measure ratio (specular_manifold.h: Path's delta convention
// against the chain integrated out) and K the count of trials.
//
// The paths it estimates (covers()) are those whose x_1 .. x_j are specular and x_{j+1} a
// non-specular surface, from a light at a finite point, at every length the depth allows: with
// j = 1 all those whose x_1 refracts, with j = 2 .. 4 (or j = 1 by a reflection) those whose
// x_{j+2} is specular too (seen through glass or
// water, which BDPT reaches only by hitting the light: under a light a few millimetres wide,
// practically never, so that leaving them to BDPT, or the paths longer than 10 edges, cost the
// water caustic at index 1.0001 0.8% of Z), and only over smooth specular shapes
// (Scene::smoothSpecularShape: not over a faceted mesh, where it came out 19% low on the water
// caustic's waves with face normals, its trials cut off at their cap). BDPT's strategies that build
// such a path are left out of the bootstrap, so that the two estimate every path once between them.
#include <cstdint>
#include <functional>

#include "common/mcmc/mutations/mutation.h"
#include "common/sampling/sampler.h"

namespace farm {

class ManifoldNextEvent {
 public:
  ManifoldNextEvent(const Scene& scene, int maxDepth);

  // Whether the scene has a smooth specular surface (Scene::smoothSpecularShape) and a light:
  // without, nothing is left to it.
  bool active() const;
  // Whether x is a path it estimates (and BDPT then does not).
  bool covers(const Path& x) const;

  // One sample; `visit` receives each path built and the luminance of its value.
  void sample(Sampler& sampler, const std::function<void(const Path&, double)>& visit) const;

  // One connection of light vertex y to surface vertex z through specular vertices, as
  // sample() makes it: a chain y S+ z drawn from a seed, and the count of further trials until
  // the same chain recurs (mean 1 / P(chain)); false where the seed gave none or the trials ran
  // past their cap. E[f(chain) * trials] is the sum of f over the chains the seeds reach, which
  // is what lets the chains' own optics be checked apart from the paths around them.
  bool sampleChain(const PathVertex& y, const PathVertex& z, bool severalAllowed, Sampler& sampler,
                   Path* chain, uint64_t* trials) const;

  uint64_t rays() const { return context_.rays; }
  // Connections given up because the trials ran past their cap (10^4): each a path of
  // probability below 1e-4 of being found, left out (a bias of that order on its share).
  uint64_t abandoned() const { return abandoned_; }

 private:
  // Where the seeds are drawn for joining y and z: near the first crossing of the segment from z
  // to y with a specular surface (if any), within sigma, or anywhere on the specular surfaces.
  struct SeedRegion {
    bool crossing = false;
    Vec3f point, normal;
    double sigma = 0;
  };
  SeedRegion seedRegion(const PathVertex& y, const PathVertex& z) const;
  // y joined to z through specular vertices from a seed: the walked chain y S+ z, or false.
  bool solve(const PathVertex& y, const PathVertex& z, bool severalAllowed,
             const SeedRegion& region, Sampler& sampler, Path* chain) const;
  // Trials until `chain` recurs (>= 1), or 0 past their cap.
  uint64_t trialsUntilRecurs(const PathVertex& y, const PathVertex& z, bool severalAllowed,
                             const SeedRegion& region, const Path& chain, Sampler& sampler) const;
  void connect(const std::vector<PathVertex>& cameraPath, double survival, Sampler& sampler,
               const std::function<void(const Path&, double)>& visit) const;

  const Scene& scene_;
  int maxDepth_, maxLength_;
  MutationContext context_;
  mutable uint64_t abandoned_ = 0;
};

}  // namespace farm
