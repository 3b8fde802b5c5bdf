#include "common/mcmc/erpt_grid_seeds.h"

#include <cmath>
#include <vector>

#include "common/transport/path_tracer.h"

namespace farm {

bool hasDensityGrid(const Scene& scene) {
  for (const MediumDescription& m : scene.description().media) {
    if (m.type == MediumDescription::Type::Grid) return true;
  }
  return false;
}

GridSeedSampler::GridSeedSampler(const Scene& scene, int maxDepth, int mediumSamples,
                                 int marchSteps, int rouletteDepth)
    : scene_(scene),
      context_{scene, maxDepth},
      mediumSamples_(std::max(mediumSamples, 1)),
      marchSteps_(std::max(marchSteps, 0)),
      rouletteDepth_(std::max(rouletteDepth, 1)) {}

double GridSeedSampler::continuationProbability(int depth) const {
  double p = 1;
  for (int i = rouletteDepth_; i < depth; ++i) p *= kContinue;
  return p;
}

void GridSeedSampler::offer(int strategy, Rng& rng,
                            const std::function<void(const GridSeed&)>& seed) {
  const int n = int(x_.vertices.size()), k = n - 1;
  if (context_.maxDepth >= 0 && k > context_.maxDepth) return;
  const TransmittanceEstimator estimator{&rng, mediumSamples_, marchSteps_};
  const PathContribution f = x_.contribution(scene_, context_.maxDepth, &estimator);
  if (!f.carriesLight()) return;
  const size_t count = size_t(n);
  std::vector<double> pL(count), pE(count);
  std::vector<char> delta(count);
  x_.densities(scene_, pL.data(), pE.data(), delta.data());
  PathMedia media;
  if (!x_.media(scene_, &media)) return;
  // The camera side's vertices x_{k-1} .. x_1, shared by both strategies, then x_0 from either
  // side (the camera walk's flight, or a light point), and the continuation decisions: the walk
  // reaches x_0 at depth k (s = 0), or x_1 at depth k - 1 (s = 1).
  double logShared = 0;
  for (int j = 1; j <= k - 1; ++j) {
    const double p = pE[size_t(j)] * x_.freeFlightDensity(scene_, media, j, false);
    if (!(p > 0) || !std::isfinite(p)) return;
    logShared += std::log(p);
  }
  const bool lightPoint = onPointLight(x_[0]);
  const double p0 = lightPoint ? 0.0
                               : pE[0] * x_.freeFlightDensity(scene_, media, 0, false) *
                                     continuationProbability(k);
  const double p1 = k >= 2 && !delta[1] ? pL[0] * continuationProbability(k - 1) : 0.0;
  const double p = strategy == 0 ? p0 : p1;
  if (!(p > 0) || !std::isfinite(p) || !std::isfinite(p0 + p1)) return;
  // Balance heuristic: w_s / p_s = 1 / (p_0 + p_1) on the shared factor.
  const double logEnergy = f.logLuminance - logShared - std::log(p0 + p1);
  if (!std::isfinite(logEnergy)) return;
  seed(GridSeed{&x_, f, std::exp(logEnergy), strategy});
}

void GridSeedSampler::visit(const Vec2f& film, Rng& rng,
                            const std::function<void(const GridSeed&)>& seed) {
  const Camera& camera = scene_.camera();
  PathVertex eye;
  eye.kind = PathVertex::Kind::Camera;
  // Through a thin lens, a lens point uniform on the lens (density 1 in the lens's measure, as
  // Path's densities take it).
  eye.p = camera.hasLens() ? camera.lensPoint(Vec2f(rng.nextFloat(), rng.nextFloat()))
                           : camera.position();
  walk_.assign(1, eye);
  const int most = context_.maxDepth >= 0 ? context_.maxDepth : kUnboundedDepth;
  PathVertex next;
  if (!flyVertex(context_, eye, scene_.hasMedia() ? scene_.cameraMedium() : -1,
                 camera.generateRay(film, eye.p).d, rng, &next))
    return;
  for (int depth = 1;; ++depth) {
    walk_.push_back(next);
    const PathVertex& v = walk_.back();
    if (v.light >= 0) {  // s = 0: the walk's path as it is, x_0 on the light
      x_.vertices.assign(walk_.rbegin(), walk_.rend());
      offer(0, rng, seed);
    }
    const bool specular = !inMedium(v) && scene_.bsdfAt(v.shape, v.uv).isDelta();
    if (!specular && depth + 1 <= most) {  // s = 1: a light point joined to v
      PathVertex light;
      const float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
      if (sampleLightVertex(scene_, rng.nextFloat(), u, &light) && !atInfinity(light) &&
          connectVertices(context_, light, v)) {
        x_.vertices.assign(1, light);
        x_.vertices.insert(x_.vertices.end(), walk_.rbegin(), walk_.rend());
        offer(1, rng, seed);
      }
    }
    if (depth >= most) return;
    if (depth >= rouletteDepth_ && !(rng.nextDouble() < kContinue)) return;
    const PathVertex& from = walk_[walk_.size() - 2];
    if (!scatterVertex(context_, v, from, v.medium, TransportMode::Radiance, false, rng, &next))
      return;
  }
}

}  // namespace farm
