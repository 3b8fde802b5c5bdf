#pragma once
// Bidirectional path tracing (Veach and Guibas 1995; Veach 1997, ch. 10): a camera subpath and a
// light subpath, connected by every (s, t) strategy, combined by multiple importance sampling.
// Densities are kept per vertex in area measure, in both directions, so that MIS weights are
// ratios of products along the path (Veach 1997, eq. 10.9).
#include <cstdint>
#include <functional>
#include <vector>

#include "common/film/splat_buffer.h"
#include "common/sampling/sampler.h"
#include "common/scene/scene.h"
#include "common/transport/path_vertex.h"

namespace farm {

enum class MisHeuristic { Balance, Power, Maximum };

class BidirectionalTracer {
 public:
  BidirectionalTracer(const Scene& scene, int maxDepth,
                      MisHeuristic heuristic = MisHeuristic::Power);

  // One bidirectional sample: both subpaths, every connection; splats carry the estimator's
  // values (camera strategies at `film`, light tracing where the light vertex projects).
  void sample(const Vec2f& film, Sampler& sampler, std::vector<Splat>* splats) const;
  // The same sample apart: light tracing's splats (t = 1) appended to *lightSplats, the camera
  // strategies' sum at `film` returned (what a pixel allocation weights apart).
  Spectrum sampleApart(const Vec2f& film, Sampler& sampler, std::vector<Splat>* lightSplats) const;

  // What each strategy of a sample built: its subpaths (the path is light[0 .. s-1] followed by
  // camera[t-1 .. 0]), its unweighted value f / p as a splat would carry it (the pixel count
  // included), its MIS weight and its film point.
  struct StrategyPath {
    const PathVertex* light;
    int s;
    const PathVertex* camera;
    int t;
    Spectrum unweighted;
    double weight;
    Vec2f film;
  };
  // The same sample as sample(), reporting every strategy that carries light to `visit`
  // instead of splatting (the seeds of path-space chains come from here).
  void visitStrategies(const Vec2f& film, Sampler& sampler,
                       const std::function<void(const StrategyPath&)>& visit) const;

  // One strategy alone, as multiplexed MLT samples it (Hachisuka et al. 2014): a camera subpath
  // of exactly t vertices and a light subpath of exactly s, without Russian roulette, connected
  // and weighted by MIS over the strategies of that path length; the splat is scaled by `scale`
  // (the inverse probability of having chosen this strategy). Nothing when a subpath ends early.
  void sampleStrategy(const Vec2f& film, Sampler& sampler, int s, int t, float scale,
                      std::vector<Splat>* splats) const;

  uint64_t rays() const { return rays_; }

 private:
  int traceCameraSubpath(const Vec2f& film, Sampler& sampler, int maxVertices, bool roulette,
                         PathVertex* path) const;
  int traceLightSubpath(Sampler& sampler, int maxVertices, bool roulette, PathVertex* path) const;
  // Extends path[0] (whose ray leaves into `medium`) by up to maxVertices - 1 vertices on
  // surfaces and in media; returns the vertex count.
  int randomWalk(Ray ray, Spectrum beta, float pdfDir, int medium, Sampler& sampler,
                 SampleStream stream, TransportMode mode, int maxVertices, bool roulette,
                 PathVertex* path) const;
  // Unweighted contribution of strategy (s, t); *film set for t == 1. Connections through media
  // take the transmittance, estimated with numbers from the camera stream.
  Spectrum connect(const PathVertex* light, const PathVertex* camera, int s, int t,
                   Sampler& sampler, Vec2f* film) const;
  // The medium a ray from v in direction w starts in.
  int mediumToward(const PathVertex& v, const Vec3f& w) const;
  // What vertex v (a surface or a medium vertex) scatters from its wo towards w: the BSDF
  // (zero where the normals disagree on w's side) or the phase function.
  Spectrum scatterValue(const PathVertex& v, const Vec3f& w, TransportMode mode) const;
  // The solid-angle density with which v's BSDF or phase function samples wTo from wFrom.
  float scatterDensity(const PathVertex& v, const Vec3f& wFrom, const Vec3f& wTo) const;
  // The transmittance between two finite vertices (1 or 0 without media: visibility).
  Spectrum unblocked(const PathVertex& a, const PathVertex& b, Sampler& sampler) const;
  double misWeight(const PathVertex* light, const PathVertex* camera, int s, int t) const;
  // Strategy (s, t) of the traced subpaths: its connection, MIS weight and splat scaling, as
  // visitStrategies() reports it; false when it carries no light.
  bool evaluateStrategy(const PathVertex* light, int s, const PathVertex* camera, int t,
                        const Vec2f& film, Sampler& sampler, StrategyPath* out) const;

  const Scene& scene_;
  int maxDepth_;
  MisHeuristic heuristic_;
  mutable uint64_t rays_ = 0;
};

}  // namespace farm
