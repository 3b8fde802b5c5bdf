#include "common/transport/path_tracer.h"

#include <cmath>

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

template <typename Add>
void PathTracer::walk(const Ray& primary, Sampler& sampler, std::vector<PathVertex>* vertices,
                      const Add& add) const {
  Spectrum beta(1.0f);
  Ray ray = primary;
  bool previousDelta = true;  // the camera ray cannot be light-sampled
  float previousPdf = 0;      // solid-angle density of the last BSDF sample
  Vec3f previousP = ray.o;
  if (vertices) {
    vertices->clear();
    PathVertex camera;
    camera.kind = PathVertex::Kind::Camera;
    camera.p = ray.o;
    vertices->push_back(camera);
  }
  for (int depth = 1;; ++depth) {
    SurfaceHit hit;
    ++rays_;
    if (!scene_.intersect(ray, &hit)) {
      const int environment = scene_.environmentLight();
      if (environment < 0) break;
      // The ray leaves the scene: the environment's radiance from its direction.
      if (vertices) vertices->push_back(vertexAtInfinity(scene_, environment, ray.o, ray.d));
      Spectrum Le = scene_.environment()->radiance(ray.d);
      if (!isBlack(Le)) {
        if (previousDelta) {
          add(beta * Le, nullptr);
        } else {
          float pdfLight = scene_.lightPickPdf(environment) * scene_.environment()->pdf(ray.d);
          add(beta * Le * powerHeuristic(previousPdf, pdfLight), nullptr);
        }
      }
      break;
    }
    const int light = scene_.lightOf(hit.shape);
    if (vertices) {
      PathVertex v;
      v.p = hit.p;
      v.n = hit.ng;
      v.ns = hit.ns;
      v.uv = hit.uv;
      v.shape = hit.shape;
      v.primitive = int(hit.primitive);
      v.light = light;
      vertices->push_back(v);
    }
    if (light >= 0) {
      Spectrum Le = scene_.emitted(light, hit.ng, -ray.d);
      if (!isBlack(Le)) {
        if (previousDelta) {
          add(beta * Le, nullptr);
        } else {
          // The same path could have come from next-event estimation: weight both (eq. 9.13).
          float d2 = lengthSquared(hit.p - previousP);
          float cosL = absDot(hit.ng, ray.d);
          float pdfLight = scene_.lightPickPdf(light) / scene_.lights()[light].area * d2 / cosL;
          add(beta * Le * powerHeuristic(previousPdf, pdfLight), nullptr);
        }
      }
    }
    if (depth >= maxDepth_) break;

    const Bsdf& bsdf = scene_.bsdfAt(hit.shape, hit.uv);
    if (bsdf.isBlack() || !sidesAgree(-ray.d, hit.ng, hit.ns)) break;
    Frame frame(hit.ns);
    Vec3f wo = frame.toLocal(-ray.d);

    // Next-event estimation: a point on a light, connected if visible.
    float uLight[4] = {sampler.next(kCameraStream), sampler.next(kCameraStream),
                       sampler.next(kCameraStream), sampler.next(kCameraStream)};
    if (!bsdf.isDelta() && depth + 1 <= maxDepth_ && !scene_.lights().empty()) {
      float pickPdf;
      int l = scene_.pickLight(uLight[0], &pickPdf);
      if (scene_.lights()[l].isPoint()) {
        // The light's position; no BSDF sample reaches a point, so no MIS.
        const PointLight& point = scene_.pointLight(l);
        const Vec3f d = point.position() - hit.p;
        const float d2 = lengthSquared(d);
        if (d2 > 0) {
          const Vec3f wiW = d / std::sqrt(d2);
          const Vec3f wi = frame.toLocal(wiW);
          const Spectrum I = point.intensity(-wiW);
          const Spectrum f = bsdf.eval(wo, wi, TransportMode::Radiance);
          if (!isBlack(I) && !isBlack(f) && sidesAgree(wiW, hit.ng, hit.ns)) {
            ++rays_;
            if (scene_.visible(hit.p, hit.ng, point.position(), Vec3f(0.0f))) {
              PathVertex lightVertex;
              if (vertices) {
                lightVertex.kind = PathVertex::Kind::Light;
                lightVertex.p = point.position();
                lightVertex.light = l;
              }
              add(beta * f * I * (std::fabs(wi.z) / (d2 * pickPdf)), &lightVertex);
            }
          }
        }
      } else if (l == scene_.environmentLight()) {
        // A direction of the environment, by its importance; unblocked, it reaches it.
        float pdfDir;
        const Vec3f wiW = scene_.environment()->sample({uLight[1], uLight[2]}, &pdfDir);
        const Vec3f wi = frame.toLocal(wiW);
        if (pdfDir > 0 && sidesAgree(wiW, hit.ng, hit.ns)) {
          const Spectrum Le = scene_.environment()->radiance(wiW);
          const Spectrum f = bsdf.eval(wo, wi, TransportMode::Radiance);
          const float pdfLight = pickPdf * pdfDir;
          if (!isBlack(Le) && !isBlack(f)) {
            ++rays_;
            if (scene_.escapes(hit.p, hit.ng, wiW)) {
              PathVertex lightVertex;
              if (vertices) lightVertex = vertexAtInfinity(scene_, l, hit.p, wiW);
              float w = powerHeuristic(pdfLight, bsdf.pdf(wo, wi));
              add(beta * f * Le * (std::fabs(wi.z) * w / pdfLight), &lightVertex);
            }
          }
        }
      } else {
        Vec3f pl, nl;
        scene_.sampleLightPoint(l, &uLight[1], &pl, &nl);
        Vec3f d = pl - hit.p;
        float d2 = lengthSquared(d);
        if (d2 > 0) {
          Vec3f wiW = d / std::sqrt(d2);
          Spectrum Le = scene_.emitted(l, nl, -wiW);
          float cosL = absDot(nl, wiW);
          Vec3f wi = frame.toLocal(wiW);
          Spectrum f = bsdf.eval(wo, wi, TransportMode::Radiance);
          if (!isBlack(Le) && !isBlack(f) && cosL > 0 && sidesAgree(wiW, hit.ng, hit.ns)) {
            float pdfLight = pickPdf / scene_.lights()[l].area * d2 / cosL;
            ++rays_;
            if (scene_.visible(hit.p, hit.ng, pl, nl)) {
              float w = powerHeuristic(pdfLight, bsdf.pdf(wo, wi));
              PathVertex lightVertex;
              if (vertices) {
                lightVertex.kind = PathVertex::Kind::Light;
                lightVertex.p = pl;
                lightVertex.n = lightVertex.ns = nl;
                lightVertex.shape = scene_.lights()[l].shape;
                lightVertex.light = l;
              }
              add(beta * f * Le * (std::fabs(wi.z) * w / pdfLight), &lightVertex);
            }
          }
        }
      }
    }

    float u[3] = {sampler.next(kCameraStream), sampler.next(kCameraStream),
                  sampler.next(kCameraStream)};
    float uRoulette = sampler.next(kCameraStream);
    BsdfSample bs;
    if (!bsdf.sample(wo, u, TransportMode::Radiance, &bs)) break;
    Vec3f wiWorld = frame.toWorld(bs.wi);
    if (!sidesAgree(wiWorld, hit.ng, hit.ns)) break;
    beta *= bs.weight;
    if (isBlack(beta)) break;
    previousDelta = bs.delta;
    previousPdf = bs.pdf;
    previousP = hit.p;
    if (depth >= kRussianRouletteDepth) {
      float q = russianRouletteSurvival(maxComponent(bs.weight));
      if (uRoulette >= q) break;
      beta /= q;
    }
    ray = scene_.spawnRay(hit.p, hit.ng, wiWorld);
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
