#include "common/mcmc/mutations/mutation.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/scene/scene.h"

namespace farm {

const char* mutationName(MutationType type) {
  switch (type) {
    case MutationType::Bidirectional:
      return "bidir";
    case MutationType::LensSubpath:
      return "lens-subpath";
    case MutationType::LensPerturbation:
      return "lens";
    case MutationType::CausticPerturbation:
      return "caustic";
    case MutationType::MultiChainPerturbation:
      return "multichain";
    case MutationType::ManifoldPerturbation:
      return "manifold";
  }
  return "?";
}

namespace {

enum class Traced { Surface, LeftTheScene, Lost };

// The ray from `from` in direction w, through null boundaries: the first surface it meets
// (*hit), or that it left the scene, or that it crossed too many boundaries to follow.
// With exactLine it leaves from the vertex itself, not from spawnRay's origin off the surface,
// and passes over a first hit within that offset (its own surface, or a neighbour's edge met
// again through rounding). A specular chain's next vertex can lie a millimetre away across a
// wave crest, and the offset (1e-5 of the scene, moved along the normal) would turn so short an
// edge by a hundredth of a radian: the chain traced would miss the law of reflection or
// refraction that the manifold walk's constraints hold it to, and no walk would find it again.
Traced traceRay(const MutationContext& context, const PathVertex& from, const Vec3f& w,
                PathVertex* hit, bool exactLine = false) {
  const Scene& scene = context.scene;
  if (!isFinite(w)) return Traced::Lost;
  Ray ray = scene.spawnRay(from.p, from.n, w);
  float passOver = 0;  // > 0: the first ray's hits nearer than this are the vertex's own
  if (exactLine) {
    passOver = length(ray.o - from.p);
    ray.o = from.p;
  }
  for (int crossing = 0; crossing < 1024; ++crossing) {
    ++context.rays;
    SurfaceHit h;
    if (!scene.intersect(ray, &h)) return Traced::LeftTheScene;
    if (passOver > 0 && h.t < passOver) {
      ray.o = from.p + w * passOver;  // on the line, past the vertex's own surface
      passOver = 0;
      continue;
    }
    passOver = 0;
    if (scene.hasMedia() && scene.isNullBoundary(h.shape)) {
      ray = scene.spawnRay(h.p, h.ng, w);
      continue;
    }
    *hit = surfaceVertex(scene, h);
    return Traced::Surface;
  }
  return Traced::Lost;
}

}  // namespace

bool traceVertex(const MutationContext& context, const PathVertex& from, const Vec3f& w,
                 PathVertex* hit) {
  return traceRay(context, from, w, hit) == Traced::Surface;
}

bool traceOrEscape(const MutationContext& context, const PathVertex& from, const Vec3f& w,
                   PathVertex* hit, bool* escaped) {
  const Scene& scene = context.scene;
  *escaped = false;
  switch (traceRay(context, from, w, hit)) {
    case Traced::Surface:
      return true;
    case Traced::LeftTheScene:
      if (scene.lights().environmentLight() < 0 || scene.hasMedia()) return false;
      *hit = vertexAtInfinity(scene, scene.lights().environmentLight(), from.p, w);
      *escaped = true;
      return true;
    case Traced::Lost:
      break;
  }
  return false;
}

bool flyVertex(const MutationContext& context, const PathVertex& from, int medium, const Vec3f& w,
               Rng& rng, PathVertex* hit) {
  const Scene& scene = context.scene;
  if (!scene.hasMedia()) return traceVertex(context, from, w, hit);
  if (!isFinite(w)) return false;
  Ray ray = scene.spawnRay(from.p, from.n, w);
  Vec3f start = from.p;  // where the stretch in the current medium begins
  for (int crossing = 0; crossing < 1024; ++crossing) {
    ++context.rays;
    SurfaceHit h;
    const bool found = scene.intersect(ray, &h);
    if (medium >= 0) {
      const float length = found ? farm::length(h.p - start) : kInfinity;
      const float uChannel = rng.nextFloat(), uDistance = rng.nextFloat();
      const float t = scene.medium(medium).sampleFreeFlight(start, w, length, uChannel, uDistance);
      // (A vertex on its predecessor, at t = 0 after rounding, would leave no direction.)
      if (t < length && t > 0) {
        *hit = PathVertex();
        hit->kind = PathVertex::Kind::Medium;
        hit->p = start + w * t;
        hit->medium = medium;
        return true;
      }
    }
    if (!found) return false;
    if (!scene.isNullBoundary(h.shape)) {
      *hit = surfaceVertex(scene, h);
      hit->medium = medium;
      return true;
    }
    medium = scene.mediumOnSide(h.shape, h.ng, w, medium);
    start = h.p;
    ray = scene.spawnRay(h.p, h.ng, w);
  }
  return false;
}

bool scatterVertex(const MutationContext& context, const PathVertex& at, const PathVertex& from,
                   int around, TransportMode mode, bool mayEscape, Rng& rng, PathVertex* next) {
  const Scene& scene = context.scene;
  if (!(lengthSquared(from.p - at.p) > 0)) return false;
  const Vec3f woWorld = directionBetween(at, from);  // `from` may be the environment's x_0
  if (inMedium(at)) {
    float pdf;
    const Vec3f w = scene.medium(at.medium).phase().sample(
        woWorld, Vec2f(rng.nextFloat(), rng.nextFloat()), &pdf);
    if (!(pdf > 0)) return false;
    return flyVertex(context, at, at.medium, w, rng, next);
  }
  const Bsdf& bsdf = scene.bsdfAt(at.shape, at.uv);
  if (bsdf.isBlack() || !scene.sidesAgree(woWorld, at.n, at.ns)) return false;
  Frame frame(at.ns);
  float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
  BsdfSample bs;
  if (!bsdf.sample(frame.toLocal(woWorld), u, mode, &bs)) return false;
  Vec3f w = normalize(frame.toWorld(bs.wi));
  if (!scene.sidesAgree(w, at.n, at.ns)) return false;
  if (mayEscape) {
    bool escaped;
    return traceOrEscape(context, at, w, next, &escaped);
  }
  return flyVertex(context, at, mediumLeaving(scene, at, w, around), w, rng, next);
}

int mediumLeaving(const Scene& scene, const PathVertex& v, const Vec3f& w, int around) {
  return v.shape >= 0 ? scene.mediumOnSide(v.shape, v.n, w, around) : around;
}

bool connectVertices(const MutationContext& context, const PathVertex& a, const PathVertex& b) {
  const Scene& scene = context.scene;
  if (atInfinity(a) || atInfinity(b)) {
    if (atInfinity(a) && atInfinity(b)) return false;
    const PathVertex& finite = atInfinity(a) ? b : a;
    PathVertex hit;
    bool escaped;
    return traceOrEscape(context, finite, directionBetween(finite, atInfinity(a) ? a : b), &hit,
                         &escaped) &&
           escaped;
  }
  ++context.rays;
  if (!scene.hasMedia()) return scene.visible(a.p, a.n, b.p, b.n);
  std::vector<MediumSegment> segments;
  int arrival;
  return scene.mediumSegments(a.p, a.n, b.p, b.n, -1, &segments, &arrival);
}

int firstNonSpecularFromCamera(const Scene& scene, const Path& x) {
  int m = x.length() - 1;
  while (m > 0 && x.isSpecular(scene, m)) --m;
  return m;
}

bool isReflection(const Path& x, int i) {
  const PathVertex& v = x[i];
  return dot(x[i - 1].p - v.p, v.ns) * dot(x[i + 1].p - v.p, v.ns) > 0;
}

bool specularBounce(const Scene& scene, const PathVertex& at, const Vec3f& from, bool reflection,
                    Vec3f* w) {
  Vec3f wo = normalize(from - at.p);
  if (!scene.sidesAgree(wo, at.n, at.ns)) return false;
  Frame frame(at.ns);
  Vec3f local;
  if (!scene.bsdfOf(at.shape).specularDirection(frame.toLocal(wo), reflection, &local))
    return false;
  *w = normalize(frame.toWorld(local));
  return scene.sidesAgree(*w, at.n, at.ns);
}

Vec3f tracedDirection(const Scene& scene, const PathVertex& from, const PathVertex& to) {
  return aimedDirection(scene, from, to.p);
}

Vec3f aimedDirection(const Scene& scene, const PathVertex& from, const Vec3f& point) {
  return normalize(point - scene.spawnRay(from.p, from.n, point - from.p).o);
}

bool sampleLightVertex(const Scene& scene, float uPick, const float u[3], PathVertex* v) {
  if (scene.lights().empty()) return false;
  float pickPdf;
  const int light = scene.lights().pick(uPick, &pickPdf);
  const Light& info = scene.lights()[size_t(light)];
  if (info.isEnvironment()) {
    // A direction towards the environment by its importance; the vertex lies along it.
    float pdf;
    const Vec3f w = scene.lights().environment()->sample(Vec2f(u[0], u[1]), &pdf);
    if (!(pdf > 0)) return false;
    *v = vertexAtInfinity(scene, light, scene.center(), w);
    return true;
  }
  *v = PathVertex();
  v->kind = PathVertex::Kind::Light;
  v->light = light;
  v->shape = info.shape;
  if (info.isPoint()) {
    v->p = scene.lights().pointLight(light).position();
  } else {
    scene.sampleLightPoint(light, u, &v->p, &v->n);
    v->ns = v->n;
  }
  return true;
}

bool traceFromEnvironment(const MutationContext& context, const PathVertex& x0, const Vec2f& u,
                          PathVertex* hit) {
  // As BDPT's light subpaths leave the environment (BidirectionalTracer::traceLightSubpath).
  PathVertex start;
  start.p = context.scene.lights().environmentDiskPoint(-x0.n, u);
  return traceVertex(context, start, x0.n, hit);
}

double angleBetween(const Vec3f& a, const Vec3f& b) {
  // atan2 of |a x b| and a . b: accurate where acos of the dot product is not (tiny angles).
  return std::atan2(double(length(cross(a, b))), double(dot(a, b)));
}

namespace {

// A perturbation's size measured back from the two paths (by projecting, or by the angle between
// traced directions) differs from the one drawn by rounding: one drawn at a bound can come out a
// hair beyond it, where the density would read 0 (and the move's ratio infinity). Within 1e-4 of
// a bound it is taken to be on it.
bool clampToRange(double* v, double lo, double hi) {
  if (!(*v >= lo * (1 - 1e-4) && *v <= hi * (1 + 1e-4))) return false;
  *v = std::min(std::max(*v, lo), hi);
  return true;
}

}  // namespace

double logAnglePerturbationDensity(double theta, double theta1, double theta2) {
  if (!clampToRange(&theta, theta1, theta2) || !(theta > 0)) return -INFINITY;
  return -std::log(2 * M_PI * std::sin(theta) * theta * std::log(theta2 / theta1));
}

Vec3f perturbDirection(const Vec3f& w, double theta1, double theta2, Rng& rng) {
  const double theta = theta2 * std::exp(std::log(theta1 / theta2) * rng.nextDouble());
  const double phi = 2 * M_PI * rng.nextDouble();
  const double st = std::sin(theta);
  Frame frame(w);
  return normalize(frame.toWorld(
      Vec3f(float(st * std::cos(phi)), float(st * std::sin(phi)), float(std::cos(theta)))));
}

double logFilmPerturbationDensity(double r, double r1, double r2) {
  if (!clampToRange(&r, r1, r2)) return -INFINITY;
  return -std::log(2 * M_PI * r * r * std::log(r2 / r1));
}

Vec2f perturbFilm(const Vec2f& film, double r1, double r2, Rng& rng) {
  const double r = r2 * std::exp(std::log(r1 / r2) * rng.nextDouble());
  const double phi = 2 * M_PI * rng.nextDouble();
  return Vec2f(film.x + float(r * std::cos(phi)), film.y + float(r * std::sin(phi)));
}

bool followSpecularChain(const MutationContext& context, const Path& x, Path* y, int from, int to,
                         const Vec3f& firstDirection) {
  const Scene& scene = context.scene;
  const int step = to > from ? 1 : -1;
  Vec3f w = firstDirection;
  for (int i = from + step;; i += step) {
    // Rays that leave a specular vertex of the chain run along the bounce's own line.
    const bool exactLine = i != from + step;
    if (traceRay(context, (*y)[i - step], w, &(*y)[i], exactLine) != Traced::Surface) return false;
    if (i == to) return !y->isSpecular(scene, i);
    if (!y->isSpecular(scene, i)) return false;
    if (!specularBounce(scene, (*y)[i], (*y)[i - step].p, isReflection(x, i), &w)) return false;
  }
}

PerturbationSizes perturbationSizes(const Camera& camera) {
  PerturbationSizes sizes;
  const double pixels = double(camera.width()) * camera.height();
  sizes.r1 = 0.1;
  sizes.r2 = std::max(1.0, std::sqrt(0.1 * pixels / M_PI));
  // The angle one pixel subtends at the image centre.
  Vec2f centre(0.5f * camera.width(), 0.5f * camera.height());
  double radiansPerPixel = angleBetween(camera.generateRay(centre).d,
                                        camera.generateRay(Vec2f(centre.x + 1, centre.y)).d);
  sizes.theta1 = radiansPerPixel * sizes.r1;
  sizes.theta2 = std::min(radiansPerPixel * sizes.r2, 0.5 * M_PI);
  return sizes;
}

}  // namespace farm
