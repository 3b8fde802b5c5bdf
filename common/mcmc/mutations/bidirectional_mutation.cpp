#include "common/mcmc/mutations/bidirectional_mutation.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/sampling/warp.h"
#include "common/scene/scene.h"
#include "common/transport/path_tracer.h"

namespace farm {

namespace {

// The range of added vertex counts for a path of n vertices losing nd of them.
bool addedRange(int n, int nd, int maxDepth, int* lo, int* hi) {
  const int kept = n - nd;
  *lo = std::max({nd == 0 ? 1 : 0, nd - BidirectionalMutation::kMaxLengthChange, 2 - kept});
  *hi = nd + BidirectionalMutation::kMaxLengthChange;
  if (maxDepth >= 0) *hi = std::min(*hi, maxDepth + 1 - kept);
  *hi = std::min(*hi, kUnboundedDepth - kept);
  return *lo <= *hi;
}

// Weights of nd = 0 .. n - 1, and n through a thin lens (zero where no added count is
// possible), and their total.
double removedWeights(int n, int maxDepth, bool lens, std::vector<double>* weights) {
  const int most = lens ? n : n - 1;
  weights->assign(size_t(most + 1), 0.0);
  double total = 0;
  for (int nd = 0; nd <= most; ++nd) {
    int lo, hi;
    if (addedRange(n, nd, maxDepth, &lo, &hi))
      total += (*weights)[size_t(nd)] = std::ldexp(1.0, -nd);
  }
  return total;
}

double addedWeight(int nd, int na) {
  return std::ldexp(1.0, -std::abs(na - nd));
}

double addedTotal(int n, int nd, int maxDepth) {
  int lo, hi;
  if (!addedRange(n, nd, maxDepth, &lo, &hi)) return 0;
  double total = 0;
  for (int na = lo; na <= hi; ++na) total += addedWeight(nd, na);
  return total;
}

// Where the deleted run of nd vertices may start: n - nd places that keep the camera, and
// through a thin lens one more that deletes it (the run ending at the camera; none when nothing
// is deleted).
int runStarts(int n, int nd, bool lens) {
  return n - nd + (lens && nd > 0 ? 1 : 0);
}

// log of the probability of the discrete choices (nd, start, na, split) for a path of n vertices.
double logChoiceProbability(int n, int nd, int na, int maxDepth, bool lens) {
  std::vector<double> weights;
  const double total = removedWeights(n, maxDepth, lens, &weights);
  if (nd < 0 || nd >= int(weights.size()) || !(weights[size_t(nd)] > 0)) return -INFINITY;
  int lo, hi;
  addedRange(n, nd, maxDepth, &lo, &hi);
  if (na < lo || na > hi) return -INFINITY;
  return std::log(weights[size_t(nd)] / total) - std::log(double(runStarts(n, nd, lens))) +
         std::log(addedWeight(nd, na) / addedTotal(n, nd, maxDepth)) - std::log(double(na + 1));
}

int sampleDiscrete(const std::vector<double>& weights, double total, Rng& rng) {
  double u = rng.nextDouble() * total, run = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    run += weights[i];
    if (u < run && weights[i] > 0) return int(i);
  }
  for (size_t i = weights.size(); i-- > 0;) {
    if (weights[i] > 0) return int(i);
  }
  return 0;
}

// Whether an edge can join y[joint - 1] (the light side's end) and y[joint]: neither end
// specular, and not the environment's direction to the camera, which reaches a point-like lens
// with probability zero (as in BDPT).
bool connectible(const Scene& scene, const Path& y, int joint) {
  if (y.isSpecular(scene, joint - 1) || y.isSpecular(scene, joint)) return false;
  return !(atInfinity(y[joint - 1]) && y[joint].kind == PathVertex::Kind::Camera);
}

}  // namespace

bool BidirectionalMutation::appliesTo(const Path& x) const {
  return x.vertices.size() >= 2;
}

bool BidirectionalMutation::propose(const Path& x, Rng& rng, Path* y,
                                    MutationRecord* record) const {
  const Scene& scene = context_.scene;
  const Camera& camera = scene.camera();
  const bool lens = camera.hasLens();
  const int n = int(x.vertices.size());
  std::vector<double> weights;
  const double total = removedWeights(n, context_.maxDepth, lens, &weights);
  if (!(total > 0)) return false;
  const int nd = sampleDiscrete(weights, total, rng);
  const int starts = runStarts(n, nd, lens);
  const int L = std::min(int(rng.nextDouble() * starts), starts - 1);
  const int E = n - L - nd;  // 0: the camera deleted, a new lens point first on its side
  int lo, hi;
  addedRange(n, nd, context_.maxDepth, &lo, &hi);
  std::vector<double> added(size_t(hi - lo + 1));
  double addedSum = 0;
  for (int na = lo; na <= hi; ++na) addedSum += added[size_t(na - lo)] = addedWeight(nd, na);
  const int na = lo + sampleDiscrete(added, addedSum, rng);
  const int sLight = std::min(int(rng.nextDouble() * (na + 1)), na);
  const int tCamera = na - sLight;
  *record = {MutationType::Bidirectional, L, E, nd, na};
  if (E == 0 && tCamera == 0) return false;  // the camera is grown from its own side only
  // The media around the kept ends, from x's walk (none without media).
  PathMedia xMedia;
  const bool media = scene.hasMedia();
  if (media && !x.media(scene, &xMedia)) return false;
  auto aroundKept = [&](int i) { return media ? xMedia.around(scene, i) : -1; };
  auto arrived = [&](const PathVertex& v) { return media ? v.medium : -1; };

  // The light side: the kept prefix, then s' vertices by light sampling, emission and BSDFs.
  y->vertices.assign(x.vertices.begin(), x.vertices.begin() + L);
  for (int j = 0; j < sLight; ++j) {
    const int index = L + j;
    PathVertex v;
    if (index == 0) {
      // A light vertex as BDPT starts its light subpaths.
      if (scene.lights().empty()) return false;
      const float uPick = rng.nextFloat();
      const float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
      if (!sampleLightVertex(scene, uPick, u, &v)) return false;
    } else if (index == 1) {
      // Its emission, as BDPT's light subpaths leave: a point light's direction by its own
      // distribution, an area light's by Lights::sampleEmission, the environment's along its
      // direction from a point of the disk facing it.
      const PathVertex& source = y->vertices[0];
      Vec2f u(rng.nextFloat(), rng.nextFloat());
      Vec3f w;
      if (atInfinity(source)) {
        if (!traceFromEnvironment(context_, source, u, &v)) return false;
        y->vertices.push_back(v);
        continue;
      }
      if (onPointLight(source)) {
        float pdf;
        w = scene.lights().pointLight(source.light).sampleDirection(u, &pdf);
        if (!(pdf > 0)) return false;
      } else {
        const Vec3f local = scene.lights().sampleEmission(source.light, u);
        if (!(local.z != 0)) return false;
        w = normalize(Frame(source.n).toWorld(local));
      }
      // The medium around the light: its shape's side, or where it sits (as BDPT's light
      // subpaths start), when the light itself was kept; the kept path's otherwise.
      const int around = L == 0 ? scene.mediumAt(source.p) : aroundKept(0);
      if (!flyVertex(context_, source, media ? mediumLeaving(scene, source, w, around) : -1, w, rng,
                     &v))
        return false;
    } else {
      const PathVertex& at = y->vertices[size_t(index - 1)];
      const int around = index - 1 < L ? aroundKept(index - 1) : arrived(at);
      if (!scatterVertex(context_, at, y->vertices[size_t(index - 2)], around,
                         TransportMode::Importance, false, rng, &v))
        return false;
    }
    y->vertices.push_back(v);
  }
  // The camera side: t' vertices grown from the kept suffix towards the light.
  std::vector<PathVertex> grown;  // in the order they were grown
  auto suffix = [&](int i) -> const PathVertex& { return x.vertices[size_t(n - E + i)]; };
  for (int j = 0; j < tCamera; ++j) {
    PathVertex v;
    if (E == 0 && j == 0) {
      // The camera deleted: a new point on the lens, uniformly.
      v = x.vertices.back();
      v.p = camera.lensPoint(Vec2f(rng.nextFloat(), rng.nextFloat()));
      grown.push_back(v);
      continue;
    }
    const PathVertex& at = j == 0 ? suffix(0) : grown[size_t(j - 1)];
    // The vertex that becomes x_0 may be the environment's, where the ray leaves the scene
    // (path-space chains take an environment only without media).
    const bool mayEscape =
        scene.lights().environmentLight() >= 0 && !media && L + sLight == 0 && j == tCamera - 1;
    if (at.kind == PathVertex::Kind::Camera) {
      Vec2f film(rng.nextFloat() * camera.width(), rng.nextFloat() * camera.height());
      const Vec3f w = camera.generateRay(film, at.p).d;
      bool escaped;
      if (mayEscape ? !traceOrEscape(context_, at, w, &v, &escaped)
                    : !flyVertex(context_, at, media ? scene.cameraMedium() : -1, w, rng, &v))
        return false;
    } else {
      // Growing past the light (nothing deleted, the whole path kept on this side): a point light
      // has no surface to scatter from, and nothing lies beyond the environment.
      if (onPointLight(at) || atInfinity(at)) return false;
      const PathVertex& from = j == 0 ? suffix(1) : (j == 1 ? suffix(0) : grown[size_t(j - 2)]);
      const int around = j == 0 ? aroundKept(n - E) : arrived(at);
      if (!scatterVertex(context_, at, from, around, TransportMode::Radiance, mayEscape, rng, &v))
        return false;
    }
    grown.push_back(v);
  }
  y->vertices.insert(y->vertices.end(), grown.rbegin(), grown.rend());
  y->vertices.insert(y->vertices.end(), x.vertices.end() - E, x.vertices.end());

  // The connecting edge between the two ends (none when the camera side reached the light).
  const int joint = L + sLight;
  if (joint == 0) return (*y)[0].light >= 0;
  const PathVertex& a = (*y)[joint - 1];
  const PathVertex& b = (*y)[joint];
  if (!connectible(scene, *y, joint)) return false;
  return connectVertices(context_, a, b);
}

double BidirectionalMutation::logDensity(const Path& from, const Path& to,
                                         const MutationRecord& r) const {
  const Scene& scene = context_.scene;
  const bool lens = scene.camera().hasLens();
  const int n = int(from.vertices.size()), nTo = int(to.vertices.size());
  if (n != r.keptLight + r.removed + r.keptCamera || nTo != r.keptLight + r.added + r.keptCamera)
    return -INFINITY;
  if (r.keptCamera == 0 && (!lens || r.removed == 0 || r.added == 0)) return -INFINITY;
  const double logChoice = logChoiceProbability(n, r.removed, r.added, context_.maxDepth, lens);
  if (!std::isfinite(logChoice)) return -INFINITY;
  std::vector<double> pL(size_t(nTo), 0.0), pE(size_t(nTo), 0.0);
  std::vector<char> delta(size_t(nTo), 0);
  to.densities(scene, pL.data(), pE.data(), delta.data());
  // A new lens point: uniform, density 1 in the lens's measure (see the header); only from the
  // camera's side (pL is 0 there).
  if (r.keptCamera == 0) pE[size_t(nTo - 1)] = 1.0;
  // In media, each new vertex's free flight from the side that grew it (the light vertex
  // itself is sampled on its light, and a lens point on the lens, without one).
  if (scene.hasMedia()) {
    PathMedia media;
    if (!to.media(scene, &media)) return -INFINITY;
    for (int j = r.keptLight; j < std::min(r.keptLight + r.added, nTo - 1); ++j) {
      if (j > 0) pL[size_t(j)] *= to.freeFlightDensity(scene, media, j, true);
      pE[size_t(j)] *= to.freeFlightDensity(scene, media, j, false);
    }
  }
  // Sum over the splits that could have grown the new vertices, in logarithms.
  double best = -INFINITY;
  std::vector<double> terms;
  // (A renewed lens point comes from the camera's side: the split that would grow it from the
  // light's is not one.)
  for (int s = 0; s <= r.added - (r.keptCamera == 0 ? 1 : 0); ++s) {
    const int joint = r.keptLight + s;
    if (joint == 0) {
      if (to[0].light < 0) continue;
    } else if (!connectible(scene, to, joint)) {
      continue;
    }
    double term = 0;
    for (int j = r.keptLight; j < r.keptLight + r.added; ++j) {
      const double p = j < joint ? pL[size_t(j)] : pE[size_t(j)];
      if (!(p > 0) || !std::isfinite(p)) {
        term = -INFINITY;
        break;
      }
      term += std::log(p);
    }
    if (!std::isfinite(term)) continue;
    terms.push_back(term);
    best = std::max(best, term);
  }
  if (!std::isfinite(best)) return -INFINITY;
  double sum = 0;
  for (double t : terms) sum += std::exp(t - best);
  return logChoice + best + std::log(sum);
}

}  // namespace farm
