#pragma once
// One render, as both sides of the farm see it. The coordinator bootstraps and plans chains; a
// worker runs ChainSpecs and reports ChainFlushes; whoever sums the flushes turns them into the
// image with imageScale(). `farm render` runs the same steps in one process.
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/chain/chain_spec.h"
#include "common/film/image.h"
#include "common/mcmc/normalization.h"
#include "common/render/render_settings.h"

namespace farm {

class Scene;

struct BootstrapResult {
  // Normalization constant Z: expected scalar contribution (luminance) of one BDPT sample, i.e.
  // the image-plane integral of luminance, and its standard error (Monte Carlo, from the
  // candidates' sample variance). Zero for pt/bdpt, which need no bootstrap.
  double normalization = 0;
  double normalizationStdError = 0;
  int64_t candidates = 0;       // candidate paths behind Z and the seeds
  int64_t pilotCandidates = 0;  // the pilot's, drawn before them to size them (bootstrap_size.h)
  // Of the candidates, connections manifold next-event estimation gave up on (each a path found
  // in fewer than one in 10^4 trials, left out of Z: ManifoldNextEvent::abandoned).
  int64_t abandonedConnections = 0;
  int64_t nonZeroCandidates = 0;  // of them, those carrying light
  // What sized the count (common/mcmc/bootstrap_size.h), when the settings did not fix it: the
  // count the time share allows and the one Z's error asks for (0: not asked).
  int64_t candidatesForTime = 0, candidatesForError = 0;
  double seconds = 0;
  // Seeds resampled in proportion to weight, one per chain: the primary-sample vector (or, for
  // mlt, the serialized path) and its scalar contribution.
  std::vector<std::vector<float>> seedSamples;
  std::vector<std::string> seedPaths;
  std::vector<double> seedContributions;

  // Z with the chains' large steps pooled in (common/mcmc/normalization.h): what the image is
  // scaled by once the chains have run; without large steps, the bootstrap's own.
  Normalization normalizationWith(const LargeStepSums& largeSteps) const {
    return pooledNormalization(normalization, normalizationStdError, candidates, largeSteps);
  }
  // Var(Z) / Z^2 of that Z, which scales every group's image alike (batch_means.h's
  // zRelativeVariance); 0 without a Z.
  double normalizationRelativeVariance(const LargeStepSums& largeSteps = LargeStepSums()) const {
    const Normalization z = normalizationWith(largeSteps);
    if (!(z.value > 0)) return 0;
    const double r = z.stdError / z.value;
    return r * r;
  }
};

struct Progress {  // reported by long stages; return false from the callback to cancel
  double fraction = 0;
};
using ProgressCallback = std::function<bool(const Progress&)>;

// The chains of a job fall into up to this many independent groups (ChainSpec::errorGroup),
// whose images' spread estimates the image's error without a reference
// (common/film/batch_means.h). More groups: a steadier estimate, and a film each on the
// coordinator.
constexpr int kErrorGroups = 4;

// Chains (or work units) of a job whose settings name none (RenderSettings::numChains 0) and
// whose plan sets none (render_plan.h, kSdsChains).
constexpr int kDefaultChains = 64;

class RenderJob {
 public:
  RenderJob(std::shared_ptr<const Scene> scene, RenderSettings settings, std::string jobId);
  ~RenderJob();

  const RenderSettings& settings() const { return settings_; }
  const Scene& scene() const { return *scene_; }
  int width() const;
  int height() const;
  // Total mutations (pssmlt) or samples (pt/bdpt) planned; < 0 with a time budget.
  int64_t plannedWork() const;

  // Coordinator, stage 1. Throws std::runtime_error with a clear message when no light reaches
  // the camera (Z = 0) or on cancellation.
  BootstrapResult bootstrap(const ProgressCallback& progress = {}) const;
  // Coordinator, stage 2: independent work units whose budgets add up to plannedWork().
  std::vector<ChainSpec> planChains(const BootstrapResult& bootstrap) const;
  // image = imageScale * (sum of all flushes' splats); workDone = mutations/samples accepted.
  double imageScale(const BootstrapResult& bootstrap, int64_t workDone) const;
  // The same with Z pooled from the bootstrap and the chains' large steps.
  double imageScale(const BootstrapResult& bootstrap, int64_t workDone,
                    const LargeStepSums& largeSteps) const;

  // Worker: runs a chain to its budget (or until onFlush returns false), calling onFlush every
  // spec.flushInterval mutations and once at the end. Deterministic for a given spec. When
  // *cancel becomes true the chain returns at once, dropping the work since its last flush (the
  // chain resumes from that flush's state).
  void runChain(const ChainSpec& spec, const std::function<bool(ChainFlush&&)>& onFlush,
                const std::atomic<bool>* cancel = nullptr) const;

  // Image from summed splats (double) and the scale above.
  Image resolve(const std::vector<double>& sums, double scale) const;
  // Rows [y0, y1) of what resolve() answers, into out (3 floats a pixel), from a film of
  // width*height*3 sums: for what reads an image a band at a time (batch_means.h).
  void resolveRows(const std::vector<double>& sums, double scale, int y0, int y1, float* out) const;
  void resolveRows(const std::vector<float>& sums, double scale, int y0, int y1, float* out) const;
  // EXR header attributes describing this render.
  // `largeSteps`: the chains' large steps, pooled into Z as imageScale() pools them.
  ImageMetadata metadata(const BootstrapResult& bootstrap, int64_t workDone, double seconds,
                         const LargeStepSums& largeSteps = LargeStepSums()) const;

 private:
  void checkRows(size_t sums, int y0, int y1) const;  // throws for rows resolveRows cannot fill
  template <class Sum>
  void resolveFilmRows(const std::vector<Sum>& sums, double scale, int y0, int y1,
                       float* out) const;
  std::vector<ChainSpec> planTiles(const BootstrapResult& bootstrap) const;  // erpt

  std::shared_ptr<const Scene> scene_;
  RenderSettings settings_;
  std::string jobId_;
};

// Loads a scene file (Mitsuba 0.6 XML) and builds the renderer's scene, applying the film
// overrides of `settings` (width/height keep the field of view). Throws std::runtime_error
// with "file:line: problem" on bad input.
std::shared_ptr<Scene> loadScene(const std::string& path, const RenderSettings& settings);

}  // namespace farm
