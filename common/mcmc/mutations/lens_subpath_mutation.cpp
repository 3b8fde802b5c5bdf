#include "common/mcmc/mutations/lens_subpath_mutation.h"

#include <cmath>
#include <vector>

#include "common/scene/scene.h"

namespace farm {

namespace {

// Whether y[first .. n-2] has the shape the walk builds: specular vertices, then a non-specular
// one at `first`, joinable to what comes before it.
bool isLensSubpath(const Scene& scene, const Path& y, int first) {
  const int n = int(y.vertices.size());
  if (first < 0 || first > n - 2 || n - 2 - first > LensSubpathMutation::kMaxSpecularChain)
    return false;
  for (int j = first + 1; j <= n - 2; ++j) {
    if (!y.isSpecular(scene, j)) return false;
  }
  if (y.isSpecular(scene, first)) return false;
  return first == 0 ? y[0].light >= 0 : !y.isSpecular(scene, first - 1);
}

}  // namespace

bool LensSubpathMutation::appliesTo(const Path& x) const {
  return x.vertices.size() >= 2 &&
         isLensSubpath(context_.scene, x, firstNonSpecularFromCamera(context_.scene, x));
}

bool LensSubpathMutation::propose(const Path& x, Rng& rng, Path* y, MutationRecord* record) const {
  const Scene& scene = context_.scene;
  const int n = int(x.vertices.size());
  const int m = firstNonSpecularFromCamera(scene, x);
  const Camera& camera = scene.camera();
  // Walk from the camera through whatever Dirac lobes the new ray meets.
  std::vector<PathVertex> walk;  // from the camera towards the light
  // Through a thin lens, from a new lens point (uniform: density 1 in the lens's measure, see
  // bidirectional_mutation.h), so that the chain moves over the lens.
  PathVertex eye = x.vertices.back();
  const bool lens = camera.hasLens();
  if (lens) eye.p = camera.lensPoint(Vec2f(rng.nextFloat(), rng.nextFloat()));
  Vec2f film(rng.nextFloat() * camera.width(), rng.nextFloat() * camera.height());
  Vec3f w = camera.generateRay(film, eye.p).d;
  PathVertex previous = eye;
  int medium = scene.hasMedia() ? scene.cameraMedium() : -1;  // the flight's
  // Where x_m is the light, a ray that leaves the scene may end on the environment (path-space
  // chains take one only without media).
  const bool mayEscape = m == 0 && scene.lights().environmentLight() >= 0 && !scene.hasMedia();
  for (;;) {
    PathVertex v;
    bool escaped = false;
    if (mayEscape ? !traceOrEscape(context_, previous, w, &v, &escaped)
                  : !flyVertex(context_, previous, medium, w, rng, &v))
      return false;
    walk.push_back(v);
    const int length = m + int(walk.size());  // edges of the path this would make
    if (context_.maxDepth >= 0 && length > context_.maxDepth) return false;
    if (escaped || inMedium(v)) break;  // the environment and media are not specular
    const Bsdf& bsdf = scene.bsdfAt(v.shape, v.uv);
    if (!bsdf.isDelta()) break;
    if (int(walk.size()) > kMaxSpecularChain) return false;
    Vec3f wo = normalize(previous.p - v.p);
    if (!scene.sidesAgree(wo, v.n, v.ns)) return false;
    Frame frame(v.ns);
    float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
    BsdfSample bs;
    if (!bsdf.sample(frame.toLocal(wo), u, TransportMode::Radiance, &bs)) return false;
    w = normalize(frame.toWorld(bs.wi));
    if (!scene.sidesAgree(w, v.n, v.ns)) return false;
    if (scene.hasMedia()) medium = mediumLeaving(scene, v, w, v.medium);
    previous = v;
  }
  y->vertices.assign(x.vertices.begin(), x.vertices.begin() + m);
  y->vertices.insert(y->vertices.end(), walk.rbegin(), walk.rend());
  y->vertices.push_back(eye);
  const int camerasRenewed = lens ? 1 : 0;
  *record = {MutationType::LensSubpath, m, 1 - camerasRenewed, n - 1 - m + camerasRenewed,
             int(walk.size()) + camerasRenewed};
  if (m == 0) return (*y)[0].light >= 0;
  return connectVertices(context_, (*y)[m - 1], (*y)[m]);
}

double LensSubpathMutation::logDensity(const Path& from, const Path& to,
                                       const MutationRecord& r) const {
  const Scene& scene = context_.scene;
  const int nTo = int(to.vertices.size());
  // The camera is kept at a pinhole and renewed on a lens, always.
  const int renewed = scene.camera().hasLens() ? 1 : 0;
  if (r.keptCamera != 1 - renewed ||
      int(from.vertices.size()) != r.keptLight + r.removed + r.keptCamera ||
      nTo != r.keptLight + r.added + r.keptCamera || r.added < 1 + renewed)
    return -INFINITY;
  if (!isLensSubpath(scene, to, r.keptLight)) return -INFINITY;
  if (context_.maxDepth >= 0 && to.length() > context_.maxDepth) return -INFINITY;
  std::vector<double> pL(size_t(nTo), 0.0), pE(size_t(nTo), 0.0);
  std::vector<char> delta(size_t(nTo), 0);
  to.densities(scene, pL.data(), pE.data(), delta.data());
  PathMedia media;
  if (scene.hasMedia() && !to.media(scene, &media)) return -INFINITY;
  double logT = 0;
  for (int j = r.keptLight; j <= nTo - 2; ++j) {
    // Each vertex's free flight from the camera's side, in media.
    const double p =
        pE[size_t(j)] * (scene.hasMedia() ? to.freeFlightDensity(scene, media, j, false) : 1.0);
    if (!(p > 0)) return -INFINITY;
    logT += std::log(p);
  }
  return logT;  // (a new lens point adds log 1)
}

}  // namespace farm
