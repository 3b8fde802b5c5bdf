#include "common/transport/seen_emission.h"

#include <cmath>

namespace farm {

SeenEmission::SeenEmission(const Scene& scene) : scene_(scene) {}

bool SeenEmission::separates(const Scene& scene) {
  return !scene.hasMedia() && !scene.camera().hasLens();
}

void SeenEmission::densities(int light, const Vec3f& y, const Vec3f& n, double* film,
                             double* lightPoint) const {
  const Camera& camera = scene_.camera();
  const Vec3f d = y - camera.position();
  const double d2 = lengthSquared(d);
  const Vec3f w = d / float(std::sqrt(d2));
  // The film point's direction density We(w), turned into an area density at y.
  *film = d2 > 0 ? double(camera.importance(camera.position(), w)) * absDot(n, w) / d2 : 0.0;
  *lightPoint = scene_.lights().startDensity(light);
}

void SeenEmission::sample(const Vec2f& film, Rng& rng, std::vector<Splat>* splats) const {
  const Camera& camera = scene_.camera();
  const float pixelCount = camera.pixelCount();
  double pFilm, pLight;

  // 1. The film point's ray: A_px Le where it hits a light first (We / p(w) = 1).
  const Ray ray = camera.generateRay(film);
  SurfaceHit hit;
  ++rays_;
  if (scene_.intersect(ray, &hit)) {
    const int light = scene_.lightOf(hit.shape);
    if (light >= 0) {
      const Spectrum Le = scene_.lights().emitted(light, hit.ng, -ray.d);
      if (!isBlack(Le)) {
        densities(light, hit.p, hit.ng, &pFilm, &pLight);
        const double weight = pFilm * pFilm / (pFilm * pFilm + pLight * pLight);
        splats->push_back({film, Le * float(pixelCount * weight)});
      }
    }
  }

  // 2. A point of a light, projected onto the film: A_px Le We cos / d^2 / p(y).
  const float uPick = rng.nextFloat();
  const float uPoint[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
  if (scene_.lights().empty()) return;
  float pickPdf;
  const int light = scene_.lights().pick(uPick, &pickPdf);
  const Light& area = scene_.lights()[size_t(light)];
  if (area.isPoint() || area.isEnvironment() || !(area.area > 0)) return;
  Vec3f y, n;
  scene_.sampleLightPoint(light, uPoint, &y, &n);
  const Vec3f toCamera = camera.position() - y;
  const float d2 = lengthSquared(toCamera);
  if (!(d2 > 0)) return;
  const Vec3f w = toCamera / std::sqrt(d2);
  const Spectrum Le = scene_.lights().emitted(light, n, w);
  Vec2f point;
  if (isBlack(Le) || !camera.project(camera.position(), -w, &point)) return;
  densities(light, y, n, &pFilm, &pLight);
  if (!(pFilm > 0) || !(pLight > 0)) return;
  ++rays_;
  if (!scene_.visible(y, n, camera.position(), Vec3f(0.0f))) return;
  const double weight = pLight * pLight / (pFilm * pFilm + pLight * pLight);
  splats->push_back({point, Le * float(pixelCount * pFilm / pLight * weight)});
}

}  // namespace farm
