#include "common/transport/bidirectional.h"

#include <cmath>
#include <limits>

#include "common/sampling/warp.h"
#include "common/transport/medium_tracking.h"
#include "common/transport/path_tracer.h"

namespace farm {

namespace {

// Converts a solid-angle density at `from` towards `to` into an area density at `to`; a vertex
// at infinity keeps the solid-angle density.
float toAreaDensity(float pdfSolidAngle, const Vec3f& from, const PathVertex& to) {
  if (atInfinity(to)) return pdfSolidAngle;
  return float(toAreaDensity(double(pdfSolidAngle), from, to.p, to.n));
}

Vec3f directionTo(const Vec3f& from, const Vec3f& to) {
  return normalize(to - from);
}

// |cos| at the light subpath's end y towards w: geometric on an emitter (s == 1), otherwise the
// shading cosine times the adjoint correction, |w.ng| |wo.ns| / |wo.ng|; none in a medium.
float lightEndCosine(const PathVertex& y, const Vec3f& w, int s) {
  if (inMedium(y)) return 1;
  if (s == 1) return absDot(y.n, w);
  return absDot(w, y.ns) * shadingCorrection(y.wo, w, y.n, y.ns);
}

// |cos| at the camera subpath's end z towards w: the shading cosine (the rendering equation's);
// none in a medium.
float cameraEndCosine(const PathVertex& z, const Vec3f& w) {
  return inMedium(z) ? 1.0f : absDot(z.ns, w);
}

}  // namespace

int BidirectionalTracer::mediumToward(const PathVertex& v, const Vec3f& w) const {
  if (v.shape < 0 || inMedium(v)) return v.medium;
  return scene_.mediumOnSide(v.shape, v.n, w, v.medium);
}

Spectrum BidirectionalTracer::scatterValue(const PathVertex& v, const Vec3f& w,
                                           TransportMode mode) const {
  if (inMedium(v)) return Spectrum(scene_.medium(v.medium).phase().eval(v.wo, w));
  if (!scene_.sidesAgree(w, v.n, v.ns)) return Spectrum(0.0f);
  const Frame frame(v.ns);
  return scene_.bsdfAt(v.shape, v.uv).eval(frame.toLocal(v.wo), frame.toLocal(w), mode);
}

float BidirectionalTracer::scatterDensity(const PathVertex& v, const Vec3f& wFrom,
                                          const Vec3f& wTo) const {
  if (inMedium(v)) return scene_.medium(v.medium).phase().eval(wFrom, wTo);
  const Frame frame(v.ns);
  return scene_.bsdfAt(v.shape, v.uv).pdf(frame.toLocal(wFrom), frame.toLocal(wTo));
}

Spectrum BidirectionalTracer::unblocked(const PathVertex& a, const PathVertex& b,
                                        Sampler& sampler) const {
  ++rays_;
  // Without media, Scene::transmittance is visibility.
  return scene_.transmittance(a.p, a.n, b.p, b.n, mediumToward(a, directionBetween(a, b)), sampler,
                              kCameraStream);
}

BidirectionalTracer::BidirectionalTracer(const Scene& scene, int maxDepth, MisHeuristic heuristic)
    : scene_(scene), maxDepth_(maxDepth < 0 ? kUnboundedDepth : maxDepth), heuristic_(heuristic) {}

int BidirectionalTracer::randomWalk(Ray ray, Spectrum beta, float pdfDir, int medium,
                                    Sampler& sampler, SampleStream stream, TransportMode mode,
                                    int maxVertices, bool roulette, PathVertex* path) const {
  int count = 1;  // path[0] is the endpoint
  // Where the ray's segment through its medium begins: the surface point, not the ray's origin
  // offset off it (see PathTracer::walk).
  Vec3f mediumStart = ray.o;
  while (count < maxVertices) {
    // The next vertex: a surface other than a null boundary, or a scattering event in the
    // medium before it.
    SurfaceHit hit;
    const MediumStep step =
        traceThroughMedia(scene_, &ray, &medium, &mediumStart, sampler, stream, &hit, &rays_);
    const bool found = step.foundSurface;
    const MediumInteraction& event = step.event;
    const Spectrum& segmentWeight = step.weight;
    beta *= segmentWeight;
    if (isBlack(beta)) break;
    PathVertex& v = path[count];
    PathVertex& prev = path[count - 1];
    if (!event.scattered && !found) {
      // A camera subpath that leaves the scene ends on the environment, at infinity: its
      // density there is the direction's.
      const int environment = scene_.lights().environmentLight();
      if (mode == TransportMode::Radiance && environment >= 0) {
        v = vertexAtInfinity(scene_, environment, ray.o, ray.d);
        v.beta = beta;
        v.pdfFwd = pdfDir;
        ++count;
      }
      break;
    }
    if (event.scattered) {
      const Vec3f p = mediumStart + ray.d * event.t;
      // Far outside the scene in a medium that fills all space: the subpath ends before the
      // vertex, or the vertex and all that follows count 1/q.
      if (roulette && !survivesBeyondReach(scene_, p, sampler, stream, &beta)) break;
      v = PathVertex();
      v.kind = PathVertex::Kind::Medium;
      v.p = p;
    } else {
      v = surfaceVertex(scene_, hit);
    }
    v.wo = -ray.d;
    v.beta = beta;
    v.medium = medium;
    // After the environment, pdfDir is the density of the disk the ray left (in the plane
    // normal to its direction): projected onto the surface by its cosine.
    v.pdfFwd = atInfinity(prev) ? pdfDir * cosineAt(v, prev.n) : toAreaDensity(pdfDir, prev.p, v);
    ++count;
    if (count >= maxVertices) break;

    float u[3] = {sampler.next(stream), sampler.next(stream), sampler.next(stream)};
    float uRoulette = sampler.next(stream);
    Vec3f wi;
    float pdfRev;
    Spectrum weight, rouletteScale(1.0f);
    if (inMedium(v)) {
      // The phase function, sampled exactly (weight one); it is symmetric, so the reverse
      // density is the forward one.
      wi = scene_.medium(medium).phase().sample(v.wo, {u[1], u[2]}, &pdfDir);
      if (!(pdfDir > 0)) break;
      pdfRev = pdfDir;
      weight = Spectrum(1.0f);
      mediumStart = v.p;
      ray = Ray{v.p, wi};
    } else {
      const Bsdf& bsdf = scene_.bsdfAt(hit.shape, hit.uv);
      if (bsdf.isBlack() || !scene_.sidesAgree(v.wo, v.n, v.ns)) break;
      Frame frame(v.ns);
      Vec3f wo = frame.toLocal(v.wo);
      BsdfSample bs;
      if (!bsdf.sample(wo, u, mode, &bs)) break;
      wi = frame.toWorld(bs.wi);
      if (!scene_.sidesAgree(wi, v.n, v.ns)) break;
      if (bs.delta) {
        // Dirac lobes: densities are not comparable with other strategies; the MIS weights skip
        // connections at this vertex and treat its densities as one (Veach 1997, 10.3.5).
        v.delta = true;
        pdfDir = 0;
        pdfRev = 0;
      } else {
        pdfDir = bs.pdf;
        pdfRev = bsdf.pdf(bs.wi, wo);
      }
      weight = rouletteScale = bs.weight;
      if (mode == TransportMode::Importance) weight *= shadingCorrection(v.wo, wi, v.n, v.ns);
      medium = scene_.mediumOnSide(hit.shape, hit.ng, wi, medium);
      mediumStart = v.p;
      ray = scene_.spawnRay(v.p, v.n, wi);
    }
    beta *= weight;
    prev.pdfRev = toAreaDensity(pdfRev, v.p, prev);
    if (roulette && count > kRussianRouletteDepth) {
      float q = russianRouletteSurvival(maxComponent(rouletteScale * segmentWeight));
      if (uRoulette >= q) break;
      beta /= q;
    }
    if (isBlack(beta) || !isFinite(beta)) break;
  }
  return count;
}

int BidirectionalTracer::traceCameraSubpath(const Vec2f& film, Sampler& sampler, int maxVertices,
                                            bool roulette, PathVertex* path) const {
  const Camera& camera = scene_.camera();
  // A thin lens's point, uniformly on its disk (its density is common to every strategy).
  const Vec3f lens =
      camera.hasLens()
          ? camera.lensPoint({sampler.next(kCameraStream), sampler.next(kCameraStream)})
          : camera.position();
  Ray ray = camera.generateRay(film, lens);
  PathVertex& c = path[0];
  c = PathVertex();
  c.kind = PathVertex::Kind::Camera;
  c.p = lens;
  c.beta = Spectrum(1.0f);  // We / pdf = 1: film points are sampled uniformly
  c.medium = scene_.cameraMedium();
  float pdfDir = camera.importance(lens, ray.d);
  return randomWalk(ray, Spectrum(1.0f), pdfDir, c.medium, sampler, kCameraStream,
                    TransportMode::Radiance, maxVertices, roulette, path);
}

int BidirectionalTracer::traceLightSubpath(Sampler& sampler, int maxVertices, bool roulette,
                                           PathVertex* path) const {
  float uPick = sampler.next(kLightStream);
  float uPoint[3] = {sampler.next(kLightStream), sampler.next(kLightStream),
                     sampler.next(kLightStream)};
  Vec2f uDir(sampler.next(kLightStream), sampler.next(kLightStream));
  if (scene_.lights().empty() || maxVertices < 1) return 0;
  float pickPdf;
  int l = scene_.lights().pick(uPick, &pickPdf);
  const Light& light = scene_.lights()[l];
  if (light.isEnvironment()) {
    // A direction w towards the environment by its importance, and a ray against it from a
    // point of the disk of the bounding sphere's radius that faces w, outside the scene.
    float pdfDir;
    const Vec3f w = scene_.lights().environment()->sample(uDir, &pdfDir);
    if (!(pdfDir > 0)) return 0;
    PathVertex& y = path[0];
    y = PathVertex();
    y.kind = PathVertex::Kind::Light;
    y.n = y.ns = -w;
    y.light = l;
    y.infinite = true;
    y.pdfFwd = pickPdf * pdfDir;
    y.beta = scene_.lights().environment()->radiance(w) / y.pdfFwd;
    y.p = scene_.lights().environmentDiskPoint(w, {uPoint[0], uPoint[1]});
    if (maxVertices < 2 || isBlack(y.beta)) return 1;
    const float pdfDisk = scene_.lights().environmentDiskDensity();
    Ray ray;
    ray.o = y.p;
    ray.d = -w;
    // The scene's outside is vacuum.
    return randomWalk(ray, y.beta / pdfDisk, pdfDisk, -1, sampler, kLightStream,
                      TransportMode::Importance, maxVertices, roulette, path);
  }
  if (light.isPoint()) {
    // The light's position, then a direction of its emission.
    const PointLight& point = scene_.lights().pointLight(l);
    PathVertex& y = path[0];
    y = PathVertex();
    y.kind = PathVertex::Kind::Light;
    y.p = point.position();
    y.light = l;
    y.medium = scene_.mediumAt(y.p);
    y.pdfFwd = pickPdf;              // the coefficient of the position's delta
    y.beta = Spectrum(1 / pickPdf);  // the intensity, by direction, comes at each connection
    if (maxVertices < 2) return 1;
    float pdfDir;
    const Vec3f w = point.sampleDirection(uDir, &pdfDir);
    const Spectrum beta = point.intensity(w) / (pickPdf * pdfDir);
    if (!(pdfDir > 0) || isBlack(beta)) return 1;
    Ray ray;
    ray.o = y.p;
    ray.d = w;
    return randomWalk(ray, beta, pdfDir, y.medium, sampler, kLightStream, TransportMode::Importance,
                      maxVertices, roulette, path);
  }
  Vec3f p, n;
  scene_.sampleLightPoint(l, uPoint, &p, &n);
  PathVertex& y = path[0];
  y = PathVertex();
  y.kind = PathVertex::Kind::Light;
  y.p = p;
  y.n = n;
  y.ns = n;
  y.shape = light.shape;
  y.light = l;
  y.medium = scene_.mediumAt(scene_.spawnRay(p, n, n).o);
  float pdfPos = float(scene_.lights().startDensity(l));
  y.pdfFwd = pdfPos;
  y.beta = light.radiance / pdfPos;
  if (maxVertices < 2) return 1;
  // Area lights emit with a cosine distribution: sample it exactly, so beta keeps pi.
  const Vec3f local = scene_.lights().sampleEmission(l, uDir);
  float pdfDir = scene_.lights().emissionPdf(l, Vec3f(0, 0, 1), local);
  if (!(pdfDir > 0)) return 1;
  Vec3f d = Frame(n).toWorld(local);
  Spectrum beta = y.beta * (std::fabs(local.z) / pdfDir);
  Ray ray = scene_.spawnRay(p, n, d);
  return randomWalk(ray, beta, pdfDir, mediumToward(y, d), sampler, kLightStream,
                    TransportMode::Importance, maxVertices, roulette, path);
}

Spectrum BidirectionalTracer::connect(const PathVertex* lightPath, const PathVertex* cameraPath,
                                      int s, int t, Sampler& sampler, Vec2f* film) const {
  if (s == 0) {  // the camera subpath found a light by itself
    const PathVertex& z = cameraPath[t - 1];
    if (z.light < 0) return Spectrum(0.0f);
    return z.beta * scene_.lights().emitted(z.light, z.n, z.wo);
  }
  const PathVertex& y = lightPath[s - 1];
  if (y.delta) return Spectrum(0.0f);
  // The camera subpath's end, when it can be connected: a non-Dirac surface or a medium vertex.
  auto connectible = [](const PathVertex& z) {
    return !z.delta && (z.kind == PathVertex::Kind::Surface || inMedium(z));
  };
  if (onPointLight(y)) {                // s == 1: the light's position, if nothing blocks it
    if (t == 1) return Spectrum(0.0f);  // point lights are invisible
    const PathVertex& z = cameraPath[t - 1];
    if (!connectible(z)) return Spectrum(0.0f);
    const Vec3f d = y.p - z.p;
    const float d2 = lengthSquared(d);
    if (!(d2 > 0)) return Spectrum(0.0f);
    const Vec3f w = d / std::sqrt(d2);  // from z towards the light
    Spectrum f = scatterValue(z, w, TransportMode::Radiance) *
                 scene_.lights().pointLight(y.light).intensity(-w);
    if (isBlack(f)) return Spectrum(0.0f);
    const Spectrum T = unblocked(z, y, sampler);
    if (isBlack(T)) return Spectrum(0.0f);
    return z.beta * f * y.beta * T * (cameraEndCosine(z, w) / d2);
  }
  if (atInfinity(y)) {                  // s == 1: the environment's direction, if nothing blocks it
    if (t == 1) return Spectrum(0.0f);  // no direction of it reaches a point-like lens
    const PathVertex& z = cameraPath[t - 1];
    if (!connectible(z)) return Spectrum(0.0f);
    const Vec3f w = -y.n;  // from z towards the environment
    Spectrum f = scatterValue(z, w, TransportMode::Radiance);
    if (isBlack(f)) return Spectrum(0.0f);
    ++rays_;
    const Spectrum T =
        scene_.transmittanceToInfinity(z.p, z.n, w, mediumToward(z, w), sampler, kCameraStream);
    if (isBlack(T)) return Spectrum(0.0f);
    return z.beta * f * y.beta * T * cameraEndCosine(z, w);
  }
  if (t == 1) {  // light tracing: connect to the camera (its lens point) and splat there
    const Camera& camera = scene_.camera();
    const PathVertex& lens = cameraPath[0];
    Vec3f toCamera = lens.p - y.p;
    float d2 = lengthSquared(toCamera);
    if (!(d2 > 0)) return Spectrum(0.0f);
    Vec3f w = toCamera / std::sqrt(d2);
    if (!camera.project(lens.p, -w, film)) return Spectrum(0.0f);
    float We = camera.importance(lens.p, -w);
    Spectrum f;
    if (s == 1) {
      f = Spectrum(scene_.lights().emissionPdf(y.light, y.n, w) > 0 ? 1.0f
                                                                    : 0.0f);  // its emitting side
    } else {
      f = scatterValue(y, w, TransportMode::Importance);
    }
    if (isBlack(f)) return Spectrum(0.0f);
    const Spectrum T = unblocked(y, lens, sampler);
    if (isBlack(T)) return Spectrum(0.0f);
    return y.beta * f * T * (We * lightEndCosine(y, w, s) / d2 * camera.pixelCount());
  }
  const PathVertex& z = cameraPath[t - 1];
  if (!connectible(z)) return Spectrum(0.0f);
  Vec3f d = y.p - z.p;
  float d2 = lengthSquared(d);
  if (!(d2 > 0)) return Spectrum(0.0f);
  Vec3f w = d / std::sqrt(d2);  // from z towards y
  Spectrum f = scatterValue(z, w, TransportMode::Radiance);
  if (isBlack(f)) return Spectrum(0.0f);
  if (s == 1) {
    f *= scene_.lights().emissionPdf(y.light, y.n, -w) > 0 ? 1.0f : 0.0f;  // its emitting side
  } else {
    f *= scatterValue(y, -w, TransportMode::Importance);
  }
  if (isBlack(f)) return Spectrum(0.0f);
  // The camera side's cosine is the shading one (the rendering equation's); the light side's
  // includes the adjoint correction for shading normals. Neither in a medium.
  float G = cameraEndCosine(z, w) * lightEndCosine(y, -w, s) / d2;
  const Spectrum T = unblocked(z, y, sampler);
  if (isBlack(T)) return Spectrum(0.0f);
  return z.beta * f * y.beta * T * G;
}

double BidirectionalTracer::misWeight(const PathVertex* lightPath, const PathVertex* cameraPath,
                                      int s, int t) const {
  // The full path x_0 .. x_{n-1} from the light to the camera. pL[i] and pE[i] are the area
  // densities of x_i when sampled from the light side and from the camera side; strategy j
  // (j light vertices) has density prod_{i<j} pL[i] prod_{i>=j} pE[i], so neighbouring
  // strategies differ by one ratio pL/pE (Veach 1997, eq. 10.9).
  const int n = s + t;
  thread_local std::vector<double> pLStore, pEStore;
  thread_local std::vector<char> deltaStore;
  thread_local std::vector<const PathVertex*> vertexStore;
  if (int(pLStore.size()) < n) {
    pLStore.resize(n), pEStore.resize(n), deltaStore.resize(n), vertexStore.resize(n);
  }
  double* pL = pLStore.data();
  double* pE = pEStore.data();
  char* delta = deltaStore.data();
  auto at = [&](int i) -> const PathVertex& {
    return i < s ? lightPath[i] : cameraPath[n - 1 - i];
  };
  if (heuristic_ == MisHeuristic::Maximum) {
    // The whole path goes to one strategy. Which one must not depend on who asks: densities
    // kept from sampling and densities recomputed at a connection differ by rounding, and where
    // strategies tie (everywhere in a spherical furnace) that rounding would give a path two
    // winners or none. So every strategy recomputes all densities from the vertices alone.
    if (n == 2 && atInfinity(at(0))) return s == 0 ? 1.0 : 0.0;  // the camera sees infinity
    for (int i = 0; i < n; ++i) vertexStore[i] = &at(i);
    pathDensities(scene_, vertexStore.data(), n, pL, pE, delta);
    return maximumHeuristicStrategy(pL, pE, delta, n, onPointLight(at(0))) == s ? 1.0 : 0.0;
  }
  for (int i = 0; i < n; ++i) {
    const PathVertex& v = at(i);
    if (i < s)
      pL[i] = v.pdfFwd, pE[i] = v.pdfRev;
    else
      pL[i] = v.pdfRev, pE[i] = v.pdfFwd;
    delta[i] = v.delta;
  }
  // Densities that change with this connection.
  const PathVertex* y = s > 0 ? &lightPath[s - 1] : nullptr;
  const PathVertex* z = t > 0 ? &cameraPath[t - 1] : nullptr;
  if (s > 0 && z) {
    // x_{s-1} sampled from the camera side: from z (whose predecessor is z_{t-2}).
    Vec3f w = directionBetween(*z, *y);
    if (t == 1) {
      pE[s - 1] = toAreaDensity(scene_.camera().importance(z->p, w), z->p, *y);
    } else {
      pE[s - 1] = toAreaDensity(scatterDensity(*z, z->wo, w), z->p, *y);
    }
    if (s > 1) {  // x_{s-2} sampled from y, arriving from z
      const PathVertex& yPrev = lightPath[s - 2];
      pE[s - 2] = toAreaDensity(scatterDensity(*y, -w, y->wo), y->p, yPrev);
    }
  }
  if (t > 0) {
    if (s == 0 && atInfinity(*z)) {
      // z is the environment: its direction's density as a light-subpath start, and the disk's
      // density projected onto z_{t-2}.
      pL[0] = float(scene_.lights().startDensity(z->light, -z->n));
      if (t > 1) {
        pL[1] = scene_.lights().environmentDiskDensity() * cosineAt(cameraPath[t - 2], z->n);
      }
    } else if (s == 0) {
      // z lies on a light: its density as a light-subpath start, and the emission towards z_{t-2}.
      pL[0] = float(scene_.lights().startDensity(z->light));
      if (t > 1) {
        const PathVertex& zPrev = cameraPath[t - 2];
        Vec3f w = directionTo(z->p, zPrev.p);
        pL[1] = toAreaDensity(scene_.lights().emissionPdf(z->light, z->n, w), z->p, zPrev);
      }
    } else {
      Vec3f w = directionBetween(*y, *z);
      float pdf;
      if (s == 1 && atInfinity(*y)) {
        pdf = 0;  // not used: the disk's density, projected, is z's
      } else if (s == 1 && onPointLight(*y)) {
        pdf = scene_.lights().pointLight(y->light).directionPdf(w);
      } else if (s == 1) {
        pdf = scene_.lights().emissionPdf(y->light, y->n, w);
      } else {
        pdf = scatterDensity(*y, y->wo, w);
      }
      pL[s] = atInfinity(*y) ? scene_.lights().environmentDiskDensity() * cosineAt(*z, y->n)
                             : toAreaDensity(pdf, y->p, *z);
      if (t > 1) {  // z_{t-2} sampled from z, arriving from y
        const PathVertex& zPrev = cameraPath[t - 2];
        pL[s + 1] = toAreaDensity(scatterDensity(*z, -w, z->wo), z->p, zPrev);
      }
    }
  }
  auto remap = [](double p) { return p != 0 ? p : 1.0; };
  double sum = 1;
  double r = 1;
  const bool power = heuristic_ == MisHeuristic::Power;
  // No strategy connects the environment to the camera directly (light tracing of a path of one
  // edge from infinity): its direction reaches a point-like lens with probability zero.
  const bool cameraSeesInfinity = n == 2 && atInfinity(at(0));
  for (int i = s; i <= n - 2; ++i) {  // strategies with more light vertices (j = i + 1)
    r *= remap(pL[i]) / remap(pE[i]);
    if (delta[i] || delta[i + 1] || cameraSeesInfinity) continue;
    sum += power ? r * r : r;
  }
  r = 1;
  const bool pointLight = onPointLight(at(0));  // no camera path reaches it: no strategy 0
  for (int i = s - 1; i >= 0; --i) {            // strategies with fewer light vertices (j = i)
    r *= remap(pE[i]) / remap(pL[i]);
    bool connectible = !delta[i] && (i == 0 || !delta[i - 1]) && !(i == 0 && pointLight);
    if (!connectible) continue;
    sum += power ? r * r : r;
  }
  return 1 / sum;
}

void BidirectionalTracer::visitStrategies(
    const Vec2f& film, Sampler& sampler,
    const std::function<void(const StrategyPath&)>& visit) const {
  const int maxVertices = maxDepth_ + 1;
  thread_local std::vector<PathVertex> cameraPath, lightPath;
  if (int(cameraPath.size()) < maxVertices + 1) cameraPath.resize(maxVertices + 1);
  if (int(lightPath.size()) < maxVertices + 1) lightPath.resize(maxVertices + 1);
  const int nCamera = traceCameraSubpath(film, sampler, maxVertices, true, cameraPath.data());
  const int nLight = traceLightSubpath(sampler, maxDepth_, true, lightPath.data());
  StrategyPath path;
  for (int t = 1; t <= nCamera; ++t) {
    for (int s = 0; s <= nLight; ++s) {
      const int edges = s + t - 1;
      if (edges < 1 || edges > maxDepth_) continue;
      if (t == 1 && s == 0) continue;
      if (evaluateStrategy(lightPath.data(), s, cameraPath.data(), t, film, sampler, &path))
        visit(path);
    }
  }
}

bool BidirectionalTracer::evaluateStrategy(const PathVertex* light, int s, const PathVertex* camera,
                                           int t, const Vec2f& film, Sampler& sampler,
                                           StrategyPath* out) const {
  Vec2f splatFilm = film;
  Spectrum c = connect(light, camera, s, t, sampler, &splatFilm);
  if (isBlack(c)) return false;
  double w = misWeight(light, camera, s, t);
  if (w <= 0) return false;
  // Camera strategies splat A_px times their value at the film point (see Camera).
  *out = {light, s, camera, t, t == 1 ? c : c * scene_.camera().pixelCount(), w, splatFilm};
  return true;
}

Spectrum BidirectionalTracer::sampleApart(const Vec2f& film, Sampler& sampler,
                                          std::vector<Splat>* lightSplats) const {
  Spectrum cameraSum(0.0f);
  visitStrategies(film, sampler, [&](const StrategyPath& p) {
    Spectrum value = p.unweighted * float(p.weight);
    if (p.t == 1)
      lightSplats->push_back({p.film, value});
    else
      cameraSum += value;
  });
  return cameraSum;
}

void BidirectionalTracer::sample(const Vec2f& film, Sampler& sampler,
                                 std::vector<Splat>* splats) const {
  // Camera strategies share the film point: one splat for their sum, after light tracing's.
  const Spectrum cameraSum = sampleApart(film, sampler, splats);
  if (!isBlack(cameraSum)) splats->push_back({film, cameraSum});
}

void BidirectionalTracer::sampleStrategy(const Vec2f& film, Sampler& sampler, int s, int t,
                                         float scale, std::vector<Splat>* splats) const {
  if (t < 1 || s < 0 || (s == 0 && t == 1) || s + t - 1 > maxDepth_) return;
  thread_local std::vector<PathVertex> cameraPath, lightPath;
  if (int(cameraPath.size()) < t) cameraPath.resize(t);
  if (int(lightPath.size()) < s + 1) lightPath.resize(s + 1);
  if (traceCameraSubpath(film, sampler, t, false, cameraPath.data()) < t) return;
  if (s > 0 && traceLightSubpath(sampler, s, false, lightPath.data()) < s) return;
  StrategyPath path;
  if (evaluateStrategy(lightPath.data(), s, cameraPath.data(), t, film, sampler, &path))
    splats->push_back({path.film, path.unweighted * float(path.weight * scale)});
}

}  // namespace farm
