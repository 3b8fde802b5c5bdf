#include "common/transport/medium_tracking.h"

namespace farm {

MediumStep traceThroughMedia(const Scene& scene, Ray* ray, int* medium, Vec3f* mediumStart,
                             Sampler& sampler, SampleStream stream, SurfaceHit* hit,
                             uint64_t* rays) {
  MediumStep step;
  for (;;) {
    ++*rays;
    step.foundSurface = scene.intersect(*ray, hit);
    if (*medium >= 0) {
      // The medium counts from the surface point, not from the ray's offset origin.
      step.event = scene.medium(*medium).sampleInteraction(
          *mediumStart, ray->d, step.foundSurface ? length(hit->p - *mediumStart) : kInfinity,
          sampler, stream);
      step.weight *= step.event.weight;
      if (step.event.scattered) {
        step.foundSurface = false;
        return step;
      }
    }
    if (!step.foundSurface || !scene.isNullBoundary(hit->shape)) return step;
    *medium = scene.mediumOnSide(hit->shape, hit->ng, ray->d, *medium);
    *ray = scene.spawnRay(hit->p, hit->ng, ray->d);
    *mediumStart = hit->p;
  }
}

}  // namespace farm
