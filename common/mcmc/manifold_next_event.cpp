#include "common/mcmc/manifold_next_event.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/mcmc/mutations/manifold_walk.h"
#include "common/mcmc/primary_sample_integrand.h"
#include "common/scene/bsdfs/fresnel.h"
#include "common/scene/scene.h"
#include "common/transport/path_tracer.h"
#include "common/transport/specular_manifold.h"

namespace farm {

namespace {

constexpr int kMaxSpecularVertices = 4;
constexpr uint64_t kMaxTrials = 10000;
// Seeds near the crossing of the segment from z to y with a specular surface, this often; the
// rest anywhere on the specular surfaces, which reaches every chain there is.
constexpr float kLocalShare = 0.9f;

// The probability with which a chain traced from a seed reflects at specular vertex v, arriving
// from `from`: the Fresnel reflectance, kept within [0.1, 0.9] so that neither lobe is starved,
// except where only one exists (a conductor; total internal reflection).
float reflectionProbability(const Scene& scene, const PathVertex& v, const Vec3f& from) {
  float intIOR, extIOR;
  if (!scene.bsdfOf(v.shape).smoothDielectricIndices(&intIOR, &extIOR)) return 1;
  float cosT;
  const float f = fresnelDielectric(dot(normalize(from - v.p), v.ns), intIOR / extIOR, &cosT);
  return f >= 1 ? 1.0f : std::min(0.9f, std::max(0.1f, f));
}

}  // namespace

ManifoldNextEvent::ManifoldNextEvent(const Scene& scene, int maxDepth)
    : scene_(scene),
      maxDepth_(maxDepth),
      maxLength_(maxDepth > 0 ? maxDepth : kUnboundedDepth),
      context_{scene, maxDepth} {}

bool ManifoldNextEvent::active() const {
  // Where every specular shape is faceted, covers() takes no path.
  return scene_.hasSmoothSpecularShape() && !scene_.lights().empty() && maxLength_ >= 3;
}

bool ManifoldNextEvent::covers(const Path& x) const {
  const int k = x.length();
  if (k < 3 || k > maxLength_) return false;
  // x_0 on a light: a light vertex, or a camera path's hit on an emitting surface.
  const PathVertex& light = x[0];
  if (light.light < 0 || atInfinity(light)) return false;
  int j = 0;  // specular vertices after the light
  while (j + 1 < k && x.isSpecular(scene_, j + 1)) ++j;
  if (j < 1 || j > kMaxSpecularVertices || x[j + 1].kind != PathVertex::Kind::Surface ||
      x.isSpecular(scene_, j + 1))
    return false;
  // Chains over a faceted specular shape stay with BDPT: each facet holds its own solution,
  // which a walk finds only from a seed on that facet, so that the trials until it recurs would
  // often pass their cap (a bias) and cost tens of thousands of walks where they do not.
  for (int i = 1; i <= j; ++i) {
    if (!scene_.smoothSpecularShape(x[i].shape)) return false;
  }
  // Through one refraction, always; otherwise (a reflection, or several specular vertices) only
  // where the diffuse vertex is seen through a specular one too (L S D S .., L S S D S ..), which
  // BDPT builds only by hitting the light. Where it is seen from a diffuse vertex or the camera,
  // BDPT's light subpaths join it well, while this estimator is noisy there: the trials of a
  // chain of several vertices (its solutions' basins small, near a caustic), and a curved
  // mirror's reflections of the light, whose value 1 / |det| grows without bound at the folds of
  // the caustic it throws (the water's reflections on the walls at index 4 were two thirds of Z's
  // variance, for 39% of Z; docs/specular.md). A refraction into water or glass bends
  // light towards the normal and spreads what a light sends through it evenly (the floor under
  // the water, lit through its surface), where this estimator's next event beats BDPT's light
  // subpaths.
  if (j == 1) {
    const Vec3f n = x[1].n;  // either side: only whether x_0 and x_2 lie on the same one counts
    const bool reflected = (dot(x[0].p - x[1].p, n) > 0) == (dot(x[2].p - x[1].p, n) > 0);
    if (!reflected) return true;
  }
  return x.isSpecular(scene_, j + 2);
}

ManifoldNextEvent::SeedRegion ManifoldNextEvent::seedRegion(const PathVertex& y,
                                                            const PathVertex& z) const {
  SeedRegion region;
  SurfaceHit hit;
  Ray ray = scene_.spawnRay(z.p, z.n, y.p - z.p);
  ray.tMax = length(y.p - ray.o);
  ++context_.rays;
  region.crossing = scene_.intersect(ray, &hit) && scene_.bsdfOf(hit.shape).isDelta();
  region.point = hit.p;
  region.normal = hit.ng;
  region.sigma = 0.1 * double(length(y.p - z.p));
  return region;
}

bool ManifoldNextEvent::solve(const PathVertex& y, const PathVertex& z, bool severalAllowed,
                              const SeedRegion& region, Sampler& sampler, Path* chain) const {
  // The seed: a point near the crossing (a Gaussian offset in its tangent plane) or anywhere on
  // the specular surfaces; four numbers either way.
  const float choice = sampler.next(kLightStream);
  float u[3] = {sampler.next(kLightStream), sampler.next(kLightStream), sampler.next(kLightStream)};
  Vec3f seed;
  if (region.crossing && choice < kLocalShare) {
    const double radius =
        region.sigma * std::sqrt(-2 * std::log(std::max(1e-12, 1.0 - double(u[0]))));
    const double phi = 2 * M_PI * double(u[1]);
    const Frame frame(region.normal);
    seed = region.point + frame.s * float(radius * std::cos(phi)) +
           frame.t * float(radius * std::sin(phi));
  } else {
    Vec3f n;
    if (!scene_.sampleSpecularSurface(u, &seed, &n)) return false;
  }
  // From y through the seed to the first surface, which must be specular; then through a lobe
  // picked at random (by its Fresnel share) at each specular vertex it meets, up to the first
  // non-specular one, where the chain ends: its structure is part of what the seed draws. The
  // walk takes that end to z.
  Vec3f w = aimedDirection(scene_, y, seed);
  if (!isFinite(w)) return false;
  Path initial;
  initial.vertices.reserve(kMaxSpecularVertices + 2);
  initial.vertices.push_back(y);
  for (;;) {
    PathVertex next;
    if (!traceVertex(context_, initial.vertices.back(), w, &next)) return false;
    initial.vertices.push_back(next);
    const int i = initial.length();
    if (!initial.isSpecular(scene_, i)) break;
    if (i > kMaxSpecularVertices) return false;
    const PathVertex& s = initial[i];
    const bool reflection =
        sampler.next(kLightStream) < reflectionProbability(scene_, s, initial[i - 1].p);
    if (!specularBounce(scene_, s, initial[i - 1].p, reflection, &w)) return false;
  }
  if (initial.length() < 2) return false;
  // A chain of several vertices that covers() would give back to BDPT: no walk for it.
  if (initial.length() > 2 && !severalAllowed) return false;
  return manifoldWalk(context_, initial, 0, initial.length(), z, chain);
}

uint64_t ManifoldNextEvent::trialsUntilRecurs(const PathVertex& y, const PathVertex& z,
                                              bool severalAllowed, const SeedRegion& region,
                                              const Path& chain, Sampler& sampler) const {
  // Trials until the same chain recurs: their count K has mean 1 / P(this chain). The same
  // chain is found again only to the walk's precision: where z lies a millimetre from the
  // specular vertex (the water line on a wall), a thousandth of that edge is below it, and
  // without the walk's tolerance the chain's own recurrences were missed and K inflated
  // (on the water caustic, 736 misses in 2^18 samples, each 0.01-5 times the walk's tolerance
  // times the chain's derivative from the recurrence).
  const double tolerance = manifoldWalkTolerance(scene_, z.p);
  for (uint64_t trials = 1; trials <= kMaxTrials; ++trials) {
    Path again;
    if (solve(y, z, severalAllowed, region, sampler, &again) &&
        again.vertices.size() == chain.vertices.size() &&
        sameSpecularChain(chain, again, 0, chain.length(), tolerance))
      return trials;
  }
  ++abandoned_;
  return 0;
}

bool ManifoldNextEvent::sampleChain(const PathVertex& y, const PathVertex& z, bool severalAllowed,
                                    Sampler& sampler, Path* chain, uint64_t* trials) const {
  const SeedRegion region = seedRegion(y, z);
  if (!solve(y, z, severalAllowed, region, sampler, chain)) return false;
  *trials = trialsUntilRecurs(y, z, severalAllowed, region, *chain, sampler);
  return *trials > 0;
}

void ManifoldNextEvent::connect(const std::vector<PathVertex>& cameraPath, double survival,
                                Sampler& sampler,
                                const std::function<void(const Path&, double)>& visit) const {
  const PathVertex& z = cameraPath.back();
  const float uPick = sampler.next(kLightStream);
  const float u[3] = {sampler.next(kLightStream), sampler.next(kLightStream),
                      sampler.next(kLightStream)};
  PathVertex y;
  if (!sampleLightVertex(scene_, uPick, u, &y)) return;
  const SeedRegion region = seedRegion(y, z);
  // Chains of several specular vertices only towards a z seen through a specular vertex.
  const bool several =
      cameraPath.size() >= 3 && scene_.bsdfOf(cameraPath[cameraPath.size() - 2].shape).isDelta();
  Path chain;
  if (!solve(y, z, several, region, sampler, &chain)) return;
  // y, the specular vertices, then z .. E: a path of this estimator's kind that carries light,
  // or nothing (and no trials spent on it).
  const int end = chain.length();
  Path x;
  x.vertices.assign(chain.vertices.begin(), chain.vertices.end() - 1);
  for (auto it = cameraPath.rbegin(); it != cameraPath.rend(); ++it) x.vertices.push_back(*it);
  if (!covers(x)) return;  // BDPT's (longer than allowed, or a chain it joins well)
  const PathContribution f = x.contribution(scene_, maxDepth_);
  if (!f.carriesLight()) return;
  const uint64_t trials = trialsUntilRecurs(y, z, several, region, chain, sampler);
  if (trials == 0) return;
  const int n = int(x.vertices.size());
  std::vector<double> pL(static_cast<size_t>(n)), pE(static_cast<size_t>(n));
  std::vector<char> delta(static_cast<size_t>(n));
  x.densities(scene_, pL.data(), pE.data(), delta.data());
  double logValue = f.logLuminance - std::log(pL[0]) -
                    logSpecularChainMeasureRatio(scene_, x, 0, end) + std::log(double(trials)) -
                    std::log(survival);
  for (int i = end; i < n - 1; ++i) logValue -= std::log(pE[size_t(i)]);
  const double value = std::exp(logValue);
  if (std::isfinite(value) && value > 0) visit(x, value);
}

void ManifoldNextEvent::sample(Sampler& sampler,
                               const std::function<void(const Path&, double)>& visit) const {
  if (!active()) return;
  const Camera& camera = scene_.camera();
  std::vector<PathVertex> cameraPath(1);
  cameraPath[0].kind = PathVertex::Kind::Camera;
  const Vec2f film = primarySampleFilmPoint(camera, sampler);
  // Through a thin lens, from a point of it, uniformly (its density is common to every
  // strategy, as in BDPT's camera subpaths).
  cameraPath[0].p =
      camera.hasLens()
          ? camera.lensPoint({sampler.next(kCameraStream), sampler.next(kCameraStream)})
          : camera.position();
  Vec3f w = camera.generateRay(film, cameraPath[0].p).d;
  double survival = 1;  // the chance the subpath has survived Russian roulette so far
  // z at `depth` edges from the camera makes a path of depth + 2 edges.
  for (int depth = 1; depth + 2 <= maxLength_; ++depth) {
    PathVertex z;
    if (!traceVertex(context_, cameraPath.back(), w, &z)) return;
    const Vec3f wo = normalize(cameraPath.back().p - z.p);
    cameraPath.push_back(z);
    const Bsdf bsdf = scene_.bsdfAt(z.shape, z.uv);
    if (!bsdf.isDelta()) connect(cameraPath, survival, sampler, visit);
    if (depth + 3 > maxLength_) return;
    const Frame frame(z.ns);
    const float u[3] = {sampler.next(kCameraStream), sampler.next(kCameraStream),
                        sampler.next(kCameraStream)};
    BsdfSample b;
    if (!scene_.sidesAgree(wo, z.n, z.ns) ||
        !bsdf.sample(frame.toLocal(wo), u, TransportMode::Radiance, &b))
      return;
    w = normalize(frame.toWorld(b.wi));
    if (!scene_.sidesAgree(w, z.n, z.ns)) return;
    // Where the depth is unbounded the subpath ends by Russian roulette, as BDPT's do, and what
    // it reaches afterwards is divided by the chance it went on (the path's density then holds
    // that chance, so the estimate stays unbiased at every length).
    if (maxDepth_ <= 0 && depth >= kRussianRouletteDepth) {
      const float q = russianRouletteSurvival(maxComponent(b.weight));
      if (sampler.next(kCameraStream) >= q) return;
      survival *= double(q);
    }
  }
}

}  // namespace farm
