#pragma once
// A path's next vertex along a ray through participating media: past null boundaries (which
// only change the medium), to the first scattering event a medium samples or the first surface
// that scatters. What path tracing and both subpaths of BDPT extend paths with.
#include <cstdint>

#include "common/sampling/sampler.h"
#include "common/scene/scene.h"

namespace farm {

struct MediumStep {
  bool foundSurface = false;  // *hit is the next vertex (a surface other than a null boundary)
  // event.scattered: the next vertex lies in the medium, at mediumStart + ray.d * event.t
  MediumInteraction event;
  Spectrum weight{1.0f};  // the product of the crossed media segments' weights
};

// Follows *ray, travelling in *medium (-1: vacuum) from *mediumStart (the surface point the
// ray's offset origin left, or its origin), to the next vertex. *ray, *medium and *mediumStart
// follow it across null boundaries. Neither a surface nor an event: the ray left the scene.
// Adds the rays traced to *rays.
MediumStep traceThroughMedia(const Scene& scene, Ray* ray, int* medium, Vec3f* mediumStart,
                             Sampler& sampler, SampleStream stream, SurfaceHit* hit,
                             uint64_t* rays);

}  // namespace farm
