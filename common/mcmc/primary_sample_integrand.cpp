#include "common/mcmc/primary_sample_integrand.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/transport/bidirectional.h"
#include "common/transport/path_tracer.h"

namespace farm {

namespace {

// A film point, then one sample of Tracer (BDPT or path tracing) through it.
template <typename Tracer>
class FilmPointIntegrand final : public PrimarySampleIntegrand {
 public:
  FilmPointIntegrand(const Scene& scene, int maxDepth) : scene_(scene), tracer_(scene, maxDepth) {}
  void evaluate(Sampler& sampler, std::vector<Splat>* splats) const override {
    tracer_.sample(primarySampleFilmPoint(scene_.camera(), sampler), sampler, splats);
  }
  uint64_t rays() const override { return tracer_.rays(); }

 private:
  const Scene& scene_;
  Tracer tracer_;
};

class MultiplexedIntegrand final : public PrimarySampleIntegrand {
 public:
  MultiplexedIntegrand(const Scene& scene, int maxDepth)
      : scene_(scene), maxDepth_(maxDepth), tracer_(scene, maxDepth) {}
  void evaluate(Sampler& sampler, std::vector<Splat>* splats) const override {
    // The technique numbers come first in the camera stream, at fixed positions, so that a
    // change of strategy does not shift the numbers the subpaths read.
    double depthProbability;
    const int depth =
        chooseMultiplexedDepth(sampler.next(kCameraStream), maxDepth_, &depthProbability);
    const int strategies = depth + 1;  // s = 0 .. depth light vertices, t = depth + 1 - s >= 1
    const int s = std::min(int(sampler.next(kCameraStream) * float(strategies)), strategies - 1);
    const Vec2f film = primarySampleFilmPoint(scene_.camera(), sampler);
    tracer_.sampleStrategy(film, sampler, s, depth + 1 - s,
                           float(double(strategies) / depthProbability), splats);
  }
  uint64_t rays() const override { return tracer_.rays(); }

 private:
  const Scene& scene_;
  int maxDepth_;
  BidirectionalTracer tracer_;
};

}  // namespace

Vec2f primarySampleFilmPoint(const Camera& camera, Sampler& sampler) {
  float x = sampler.next(kCameraStream) * camera.width();
  float y = sampler.next(kCameraStream) * camera.height();
  return Vec2f(std::min(x, std::nextafter(float(camera.width()), 0.0f)),
               std::min(y, std::nextafter(float(camera.height()), 0.0f)));
}

int chooseMultiplexedDepth(float u, int maxDepth, double* probability) {
  // Geometric, truncated to 1..cap: P(depth = k) = (1 - q) q^(k - 1) / (1 - q^cap), by
  // inversion. Unbounded, the cap is never reached in practice (q^4095 underflows) but keeps the
  // depth finite.
  const double q = kMultiplexedDepthRatio;
  const int cap = maxDepth > 0 ? maxDepth : kUnboundedDepth;
  const double mass = -std::expm1(double(cap) * std::log(q));  // 1 - q^cap
  int depth = 1 + int(std::floor(std::log1p(-double(u) * mass) / std::log(q)));
  depth = std::clamp(depth, 1, cap);
  *probability = (1 - q) * std::pow(q, depth - 1) / mass;
  return depth;
}

std::unique_ptr<PrimarySampleIntegrand> makePrimarySampleIntegrand(Algorithm algorithm,
                                                                   const Scene& scene,
                                                                   int maxDepth) {
  switch (algorithm) {
    case Algorithm::PSSMLT:
    case Algorithm::MLT:  // path-space MLT bootstraps from BDPT
      return std::make_unique<FilmPointIntegrand<BidirectionalTracer>>(scene, maxDepth);
    case Algorithm::PSSMLTOverPT:
    case Algorithm::ERPT:  // ERPT's Z is the mean energy of a path-traced seed
      return std::make_unique<FilmPointIntegrand<PathTracer>>(scene, maxDepth);
    case Algorithm::MMLT:
      return std::make_unique<MultiplexedIntegrand>(scene, maxDepth);
    default:
      throw std::invalid_argument(std::string("algorithm ") + algorithmName(algorithm) +
                                  " has no primary-sample integrand");
  }
}

double evaluateContribution(const PrimarySampleIntegrand& integrand, Sampler& sampler,
                            std::vector<Splat>* splats, InvalidSplats* rejected) {
  splats->clear();
  integrand.evaluate(sampler, splats);
  double sum = 0;
  size_t kept = 0;
  for (const Splat& s : *splats) {
    if (!rejected->check(s.value)) continue;
    (*splats)[kept++] = s;
    sum += luminance(s.value);
  }
  splats->resize(kept);
  return sum;
}

}  // namespace farm
