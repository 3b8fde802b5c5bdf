#include "common/transport/path_vertex.h"

#include <cmath>

#include "common/sampling/warp.h"
#include "common/scene/scene.h"

namespace farm {

double toAreaDensity(double pdfSolidAngle, const Vec3f& from, const Vec3f& to, const Vec3f& toN) {
  Vec3f d = to - from;
  double d2 = double(lengthSquared(d));
  if (!(d2 > 0)) return 0;
  double cosTo = lengthSquared(toN) > 0 ? double(absDot(toN, d)) / std::sqrt(d2) : 1.0;
  return pdfSolidAngle * cosTo / d2;
}

PathVertex surfaceVertex(const Scene& scene, const SurfaceHit& hit) {
  PathVertex v;
  v.kind = PathVertex::Kind::Surface;
  v.p = hit.p;
  v.n = hit.ng;
  v.ns = hit.ns;
  v.uv = hit.uv;
  v.shape = hit.shape;
  v.primitive = int(hit.primitive);
  v.light = scene.lightOf(hit.shape);
  return v;
}

PathVertex vertexAtInfinity(const Scene& scene, int light, const Vec3f& from, const Vec3f& w) {
  PathVertex v;
  v.kind = PathVertex::Kind::Light;
  v.n = v.ns = -w;
  // Far beyond the scene along w: never used for directions (directionBetween), only finite.
  v.p = from + w * (4 * scene.extent() + length(from - scene.center()));
  v.wo = -w;
  v.light = light;
  v.infinite = true;
  return v;
}

namespace {

// Solid-angle density of leaving surface vertex v in direction wTo, having arrived from
// direction wFrom (both unit, pointing away from v). For a Dirac BSDF, the coefficient of the
// delta function: the probability of the lobe that does it (zero when none does), with the
// delta taken, as in Path::contribution, in the direction towards the light. Sampling from the
// light side puts it in the other direction: the lobe's solid-angle ratio converts it.
double scatterPdf(const Scene& scene, const PathVertex& v, const Vec3f& wFrom, const Vec3f& wTo,
                  bool fromLightSide) {
  if (inMedium(v)) return scene.medium(v.medium).phase().eval(wFrom, wTo);
  Frame frame(v.ns);
  Vec3f wo = frame.toLocal(wFrom);
  Vec3f wi = frame.toLocal(wTo);
  const Bsdf& bsdf = scene.bsdfAt(v.shape, v.uv);
  if (!bsdf.isDelta()) return bsdf.pdf(wo, wi);
  bool reflection;
  float probability;
  Spectrum value;
  if (!bsdf.specularLobe(wo, wi, TransportMode::Radiance, &reflection, &probability, &value))
    return 0;
  return fromLightSide ? double(probability) * bsdf.diracJacobian(wo, wi) : double(probability);
}

// A solid-angle density at `from` in the direction of `to`, as a density of `to`: in area
// measure, except at infinity, where densities stay solid-angle ones.
double densityAt(double pdfSolidAngle, const PathVertex& from, const PathVertex& to) {
  if (atInfinity(to)) return pdfSolidAngle;
  return toAreaDensity(pdfSolidAngle, from.p, to.p, to.n);
}

}  // namespace

void pathDensities(const Scene& scene, const PathVertex* const* x, int n, double* pL, double* pE,
                   char* delta) {
  for (int i = 0; i < n; ++i) {
    const PathVertex& v = *x[i];
    delta[i] = v.kind == PathVertex::Kind::Surface && scene.bsdfOf(v.shape).isDelta();
    pL[i] = pE[i] = 0;
  }
  if (n < 2) return;
  // From the light side: x_0 by light selection and uniform area sampling, x_1 by cosine
  // emission, the rest by BSDF sampling at their predecessor.
  const PathVertex& x0 = *x[0];
  if (atInfinity(x0)) {
    // The environment: its direction's density, then the disk's projected onto x_1.
    const EnvironmentLight* environment = scene.lights().environment();
    pL[0] = environment ? scene.lights().startDensity(x0.light, -x0.n) : 0.0;
    if (n > 2)
      pL[1] = double(scene.lights().environmentDiskDensity()) * double(cosineAt(*x[1], x0.n));
  } else if (onPointLight(x0)) {
    // The position's delta coefficient, then the emission's direction density.
    pL[0] = scene.lights().startDensity(x0.light);
    const Vec3f w = normalize(x[1]->p - x0.p);
    pL[1] =
        toAreaDensity(scene.lights().pointLight(x0.light).directionPdf(w), x0.p, x[1]->p, x[1]->n);
  } else if (x0.light >= 0) {
    pL[0] = scene.lights().startDensity(x0.light);
    Vec3f w = normalize(x[1]->p - x0.p);
    pL[1] = toAreaDensity(scene.lights().emissionPdf(x0.light, x0.n, w), x0.p, x[1]->p, x[1]->n);
  }
  for (int i = 2; i < n - 1; ++i) {
    const PathVertex& prev = *x[i - 1];
    pL[i] = densityAt(scatterPdf(scene, prev, directionBetween(prev, *x[i - 2]),
                                 directionBetween(prev, *x[i]), true),
                      prev, *x[i]);
  }
  // From the camera side: x_{n-2} through the camera's importance (a direction density), the
  // rest by BSDF sampling at their successor. The pinhole itself has no density (pE = 0).
  const PathVertex& camera = *x[n - 1];
  pE[n - 2] = densityAt(scene.camera().importance(camera.p, directionBetween(camera, *x[n - 2])),
                        camera, *x[n - 2]);
  for (int i = n - 3; i >= 0; --i) {
    const PathVertex& next = *x[i + 1];
    pE[i] = densityAt(scatterPdf(scene, next, directionBetween(next, *x[i + 2]),
                                 directionBetween(next, *x[i]), false),
                      next, *x[i]);
  }
  if (onPointLight(x0)) pE[0] = 0;  // no camera path reaches a point
}

int maximumHeuristicStrategy(const double* pL, const double* pE, const char* delta, int n,
                             bool pointLight) {
  // Strategy s has density prod_{i<s} pL[i] prod_{i>=s} pE[i]. A vertex sampled through a
  // Dirac lobe counts as one on either side (Veach 1997, 10.3.5), the pinhole as well; a zero
  // density elsewhere means the strategy cannot build the path. Strategies that would connect
  // through a Dirac vertex cannot build it either.
  //
  // Strategies often tie exactly (in a spherical furnace all of them do, everywhere), and each
  // strategy sees the path through its own vertices, equal up to rounding. So densities are
  // compared on a grid of 1% in the logarithm, ties going to fewer light vertices: rounding
  // decides only for paths within rounding of a grid line, and the comparison stays a total
  // order (a band around each pairwise comparison would not be transitive: 1, 1.008, 1.016).
  constexpr double kGrid = 0.01;
  auto sampledFromLight = [&](int i) { return i > 0 && delta[i - 1]; };
  auto sampledFromCamera = [&](int i) { return i == n - 1 || (i + 1 < n && delta[i + 1]); };
  int best = -1;
  long long bestLevel = 0;
  for (int s = 0; s <= n - 1; ++s) {  // t = n - s >= 1 camera vertices
    bool possible = s == 0 ? pL[0] > 0 && !pointLight : !delta[s - 1] && !delta[s];
    double logDensity = 0;
    for (int i = 0; i < n && possible; ++i) {
      const bool fromLight = i < s;
      if (fromLight ? sampledFromLight(i) : sampledFromCamera(i)) continue;
      const double p = fromLight ? pL[i] : pE[i];
      if (!(p > 0) || !std::isfinite(p))
        possible = false;
      else
        logDensity += std::log(p);
    }
    if (!possible) continue;
    const long long level = std::llround(logDensity / kGrid);
    if (best < 0 || level > bestLevel) {
      best = s;
      bestLevel = level;
    }
  }
  return best;
}

}  // namespace farm
