#include "common/transport/path_tracer.h"

#include <cmath>
#include <stdexcept>

#include "common/transport/medium_tracking.h"

namespace farm {

namespace {
float powerHeuristic(float a, float b) {
  float a2 = a * a, b2 = b * b;
  if (std::isinf(a2)) return 1;
  return a2 > 0 ? a2 / (a2 + b2) : 0;
}
}  // namespace

PathTracer::PathTracer(const Scene& scene, int maxDepth)
    : scene_(scene), maxDepth_(maxDepth < 0 ? kUnboundedDepth : maxDepth) {}

template <typename Scatter, typename Add>
void PathTracer::nextEvent(const Vec3f& p, const Vec3f& n, const Spectrum& beta,
                           const float uLight[4], Sampler& sampler, const Scatter& scatter,
                           bool record, const Add& add) const {
  float pickPdf;
  const int l = scene_.lights().pick(uLight[0], &pickPdf);
  Spectrum fs;
  float scatterPdf;
  int medium;
  if (scene_.lights()[l].isPoint()) {
    // The light's position; no scattering sample reaches a point, so no MIS.
    const PointLight& point = scene_.lights().pointLight(l);
    const Vec3f d = point.position() - p;
    const float d2 = lengthSquared(d);
    if (!(d2 > 0)) return;
    const Vec3f wiW = d / std::sqrt(d2);
    const Spectrum I = point.intensity(-wiW);
    if (isBlack(I) || !scatter(wiW, &fs, &scatterPdf, &medium)) return;
    ++rays_;
    const Spectrum T =
        scene_.transmittance(p, n, point.position(), Vec3f(0.0f), medium, sampler, kCameraStream);
    if (isBlack(T)) return;
    PathVertex lightVertex;
    if (record) {
      lightVertex.kind = PathVertex::Kind::Light;
      lightVertex.p = point.position();
      lightVertex.light = l;
    }
    add(beta * fs * I * T / (d2 * pickPdf), &lightVertex);
  } else if (l == scene_.lights().environmentLight()) {
    // A direction of the environment, by its importance; unblocked, it reaches it.
    float pdfDir;
    const Vec3f wiW = scene_.lights().environment()->sample({uLight[1], uLight[2]}, &pdfDir);
    if (!(pdfDir > 0)) return;
    const Spectrum Le = scene_.lights().environment()->radiance(wiW);
    if (isBlack(Le) || !scatter(wiW, &fs, &scatterPdf, &medium)) return;
    const float pdfLight = pickPdf * pdfDir;
    ++rays_;
    const Spectrum T = scene_.transmittanceToInfinity(p, n, wiW, medium, sampler, kCameraStream);
    if (isBlack(T)) return;
    PathVertex lightVertex;
    if (record) lightVertex = vertexAtInfinity(scene_, l, p, wiW);
    add(beta * fs * Le * T * (powerHeuristic(pdfLight, scatterPdf) / pdfLight), &lightVertex);
  } else {
    Vec3f pl, nl;
    scene_.sampleLightPoint(l, &uLight[1], &pl, &nl);
    const Vec3f d = pl - p;
    const float d2 = lengthSquared(d);
    if (!(d2 > 0)) return;
    const Vec3f wiW = d / std::sqrt(d2);
    const Spectrum Le = scene_.lights().emitted(l, nl, -wiW);
    const float cosL = absDot(nl, wiW);
    if (isBlack(Le) || !(cosL > 0) || !scatter(wiW, &fs, &scatterPdf, &medium)) return;
    const float pdfLight = float(scene_.lights().startDensity(l)) * d2 / cosL;
    ++rays_;
    const Spectrum T = scene_.transmittance(p, n, pl, nl, medium, sampler, kCameraStream);
    if (isBlack(T)) return;
    PathVertex lightVertex;
    if (record) {
      lightVertex.kind = PathVertex::Kind::Light;
      lightVertex.p = pl;
      lightVertex.n = lightVertex.ns = nl;
      lightVertex.shape = scene_.lights()[l].shape;
      lightVertex.light = l;
    }
    add(beta * fs * Le * T * (powerHeuristic(pdfLight, scatterPdf) / pdfLight), &lightVertex);
  }
}

template <typename Add>
void PathTracer::walk(const Ray& primary, Sampler& sampler, std::vector<PathVertex>* vertices,
                      const Add& add) const {
  // Paths through media are not recorded vertex by vertex yet: ERPT, the only caller that asks
  // for vertices, refuses scenes with media when it loads them.

  Spectrum beta(1.0f);
  Ray ray = primary;
  int medium = scene_.cameraMedium();  // the medium the ray travels in (-1: vacuum)
  // Where the ray's segment through its medium begins: the ray's origin is offset off the
  // surface it leaves, the medium counts from the surface point itself.
  Vec3f mediumStart = ray.o;
  bool previousDelta = true;  // the camera ray cannot be light-sampled
  float previousPdf = 0;      // solid-angle density of the last BSDF or phase sample
  Vec3f previousP = ray.o;
  if (vertices) {
    vertices->clear();
    PathVertex camera;
    camera.kind = PathVertex::Kind::Camera;
    camera.p = ray.o;
    vertices->push_back(camera);
  }
  for (int depth = 1;; ++depth) {
    // The next vertex: the first surface along the ray that is not a null boundary, or a
    // scattering event in a medium before it.
    SurfaceHit hit;
    const MediumStep step = traceThroughMedia(scene_, &ray, &medium, &mediumStart, sampler,
                                              kCameraStream, &hit, &rays_);
    const bool found = step.foundSurface;
    const MediumInteraction& event = step.event;
    const Spectrum& segmentWeight = step.weight;
    beta *= segmentWeight;
    if (isBlack(beta)) break;

    if (event.scattered) {
      // A vertex in the medium: the phase function scatters, next-event estimation as at a
      // surface, with the phase function for the BSDF and no cosine.
      if (depth >= maxDepth_) break;
      const Vec3f p = mediumStart + ray.d * event.t;
      // Far outside the scene in a medium that fills all space: roulette before the vertex's
      // own next-event estimation, with a number of its own.
      if (!survivesBeyondReach(scene_, p, sampler, kCameraStream, &beta)) break;
      if (vertices) {
        PathVertex v;
        v.kind = PathVertex::Kind::Medium;
        v.p = p;
        v.medium = medium;
        vertices->push_back(v);
      }
      const HenyeyGreenstein phase = scene_.medium(medium).phase();
      const Vec3f wo = -ray.d;
      float uLight[4] = {sampler.next(kCameraStream), sampler.next(kCameraStream),
                         sampler.next(kCameraStream), sampler.next(kCameraStream)};
      if (depth + 1 <= maxDepth_ && !scene_.lights().empty()) {
        nextEvent(
            p, Vec3f(0.0f), beta, uLight, sampler,
            [&](const Vec3f& wiW, Spectrum* f, float* pdf, int* toward) {
              *pdf = phase.eval(wo, wiW);
              *f = Spectrum(*pdf);
              *toward = medium;
              return *pdf > 0;
            },
            vertices != nullptr, add);
      }
      const Vec2f u(sampler.next(kCameraStream), sampler.next(kCameraStream));
      const float uRoulette = sampler.next(kCameraStream);
      float pdf;
      const Vec3f wi = phase.sample(wo, u, &pdf);
      if (!(pdf > 0)) break;
      previousDelta = false;
      previousPdf = pdf;
      previousP = p;
      if (depth >= kRussianRouletteDepth) {
        const float q = russianRouletteSurvival(maxComponent(segmentWeight));
        if (uRoulette >= q) break;
        beta /= q;
      }
      ray = Ray{p, wi};
      mediumStart = p;
      continue;
    }

    if (!found) {
      const int environment = scene_.lights().environmentLight();
      if (environment < 0) break;
      // The ray leaves the scene: the environment's radiance from its direction.
      if (vertices) vertices->push_back(vertexAtInfinity(scene_, environment, ray.o, ray.d));
      Spectrum Le = scene_.lights().environment()->radiance(ray.d);
      if (!isBlack(Le)) {
        if (previousDelta) {
          add(beta * Le, nullptr);
        } else {
          float pdfLight = float(scene_.lights().startDensity(environment, ray.d));
          add(beta * Le * powerHeuristic(previousPdf, pdfLight), nullptr);
        }
      }
      break;
    }
    const int light = scene_.lightOf(hit.shape);
    if (vertices) vertices->push_back(surfaceVertex(scene_, hit));
    if (light >= 0) {
      Spectrum Le = scene_.lights().emitted(light, hit.ng, -ray.d);
      if (!isBlack(Le)) {
        if (previousDelta) {
          add(beta * Le, nullptr);
        } else {
          // The same path could have come from next-event estimation: weight both (eq. 9.13).
          float d2 = lengthSquared(hit.p - previousP);
          float cosL = absDot(hit.ng, ray.d);
          float pdfLight = float(scene_.lights().startDensity(light)) * d2 / cosL;
          add(beta * Le * powerHeuristic(previousPdf, pdfLight), nullptr);
        }
      }
    }
    if (depth >= maxDepth_) break;

    const Bsdf& bsdf = scene_.bsdfAt(hit.shape, hit.uv);
    if (bsdf.isBlack() || !scene_.sidesAgree(-ray.d, hit.ng, hit.ns)) break;
    Frame frame(hit.ns);
    Vec3f wo = frame.toLocal(-ray.d);

    // Next-event estimation: a point on a light, connected if visible.
    float uLight[4] = {sampler.next(kCameraStream), sampler.next(kCameraStream),
                       sampler.next(kCameraStream), sampler.next(kCameraStream)};
    if (!bsdf.isDelta() && depth + 1 <= maxDepth_ && !scene_.lights().empty()) {
      nextEvent(
          hit.p, hit.ng, beta, uLight, sampler,
          [&](const Vec3f& wiW, Spectrum* f, float* pdf, int* toward) {
            if (!scene_.sidesAgree(wiW, hit.ng, hit.ns)) return false;
            const Vec3f wi = frame.toLocal(wiW);
            *f = bsdf.eval(wo, wi, TransportMode::Radiance) * std::fabs(wi.z);
            if (isBlack(*f)) return false;
            *pdf = bsdf.pdf(wo, wi);
            *toward = scene_.mediumOnSide(hit.shape, hit.ng, wiW, medium);
            return true;
          },
          vertices != nullptr, add);
    }

    float u[3] = {sampler.next(kCameraStream), sampler.next(kCameraStream),
                  sampler.next(kCameraStream)};
    float uRoulette = sampler.next(kCameraStream);
    BsdfSample bs;
    if (!bsdf.sample(wo, u, TransportMode::Radiance, &bs)) break;
    Vec3f wiWorld = frame.toWorld(bs.wi);
    if (!scene_.sidesAgree(wiWorld, hit.ng, hit.ns)) break;
    beta *= bs.weight;
    if (isBlack(beta)) break;
    previousDelta = bs.delta;
    previousPdf = bs.pdf;
    previousP = hit.p;
    if (depth >= kRussianRouletteDepth) {
      float q = russianRouletteSurvival(maxComponent(bs.weight * segmentWeight));
      if (uRoulette >= q) break;
      beta /= q;
    }
    medium = scene_.mediumOnSide(hit.shape, hit.ng, wiWorld, medium);
    ray = scene_.spawnRay(hit.p, hit.ng, wiWorld);
    mediumStart = hit.p;
  }
}

Ray PathTracer::primaryRay(const Vec2f& film, Sampler& sampler) const {
  const Camera& camera = scene_.camera();
  if (!camera.hasLens()) return camera.generateRay(film);
  // A thin lens's point, uniformly on its disk.
  return camera.generateRay(
      film, camera.lensPoint({sampler.next(kCameraStream), sampler.next(kCameraStream)}));
}

Spectrum PathTracer::radiance(const Ray& primary, Sampler& sampler) const {
  Spectrum L(0.0f);
  walk(primary, sampler, nullptr, [&](const Spectrum& value, const PathVertex*) { L += value; });
  return L;
}

void PathTracer::TracedPath::assignTo(Path* x) const {
  x->vertices.clear();
  if (light) x->vertices.push_back(*light);
  x->vertices.insert(x->vertices.end(), camera, camera + count);
}

void PathTracer::visitPaths(const Vec2f& film, Sampler& sampler,
                            const std::function<void(const TracedPath&)>& visit) const {
  thread_local std::vector<PathVertex> vertices;
  const float pixelCount = scene_.camera().pixelCount();
  walk(primaryRay(film, sampler), sampler, &vertices,
       [&](const Spectrum& value, const PathVertex* light) {
         // The camera side in walk order is camera, x_1, x_2, ...: reversed, light first.
         thread_local std::vector<PathVertex> reversed;
         reversed.assign(vertices.rbegin(), vertices.rend());
         visit({light, reversed.data(), int(reversed.size()), value * pixelCount});
       });
}

void PathTracer::sample(const Vec2f& film, Sampler& sampler, std::vector<Splat>* splats) const {
  Spectrum L = radiance(primaryRay(film, sampler), sampler);
  if (!isBlack(L)) splats->push_back({film, L * scene_.camera().pixelCount()});
}

}  // namespace farm
