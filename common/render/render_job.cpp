#include "common/render/render_job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "common/chain/chain_flusher.h"
#include "common/film/splat_buffer.h"
#include "common/mcmc/bootstrap.h"
#include "common/mcmc/bootstrap_size.h"
#include "common/mcmc/erpt.h"
#include "common/mcmc/mlt_chain.h"
#include "common/mcmc/pssmlt_chain.h"
#include "common/plan/scene_analysis.h"
#include "common/scene/film_override.h"
#include "common/scene/loaders/scene_loader.h"
#include "common/scene/scene.h"
#include "common/transport/bidirectional.h"
#include "common/transport/path.h"
#include "common/transport/path_tracer.h"
#include "common/transport/seen_emission.h"

namespace farm {

namespace {

// A seed's contribution as the job reports it: through grids, marched at a step fine enough
// for a report.
const TransmittanceEstimator kSeedEstimate{nullptr, 1, 64};

constexpr uint64_t kSampleDomain = 0x5a3b;
constexpr uint64_t kPathSeedDomain = 0x9a7b;
// Time-budgeted sample chains draw from disjoint index ranges this far apart.
constexpr int64_t kUnboundedChainStride = int64_t(1) << 40;

std::string formatDouble(double v) {
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

// Independent samples (pt, bdpt): sample k of the job uses RNG stream (seed, k). With a sample
// budget, sample k lands in pixel k mod pixels (each pixel gets exactly spp samples, stratified
// by order); with a time budget the film point is uniform over the image, so that stopping at
// any count leaves the image unbiased. With a pixel allocation the film point is drawn from it,
// budget or not, and the allocation's cell says which estimator takes the sample.
void runSampleChain(const Scene& scene, const ChainSpec& spec,
                    const std::function<bool(ChainFlush&&)>& onFlush,
                    const std::atomic<bool>* cancel) {
  const Camera& camera = scene.camera();
  const int64_t pixels = int64_t(camera.width()) * camera.height();
  PathTracer pt(scene, spec.maxDepth);
  BidirectionalTracer bdpt(scene, spec.maxDepth);
  ChainFlusher flusher(spec, scene, onFlush, cancel);
  const PixelAllocation* allocation = spec.pixelAllocation.get();
  if (allocation &&
      (allocation->width() != camera.width() || allocation->height() != camera.height())) {
    throw std::invalid_argument("pixel allocation of " + std::to_string(allocation->width()) + "x" +
                                std::to_string(allocation->height()) + " for a film of " +
                                std::to_string(camera.width()) + "x" +
                                std::to_string(camera.height()));
  }
  std::vector<Splat> splats;
  while (flusher.budgetLeft()) {
    const int64_t k = spec.firstSample + flusher.done();
    Rng rng(spec.seed, streamId(kSampleDomain, uint64_t(k)));
    IndependentSampler sampler(&rng);
    splats.clear();
    if (allocation) {
      // Each sample lands where the allocation says, by its own estimator, weighted by (1) and
      // 1 / F_B of common/film/pixel_allocation.h.
      const float u0 = rng.nextFloat(), u1 = rng.nextFloat(), u2 = rng.nextFloat();
      const PixelAllocation::FilmSample at = allocation->sampleFilm(u0, u1, u2);
      if (at.bidirectional) {
        const Spectrum cameraSum = bdpt.sampleApart(at.film, sampler, &splats);
        splats.erase(
            std::remove_if(splats.begin(), splats.end(),
                           [&](const Splat& s) { return !allocation->bidirectionalAt(s.film); }),
            splats.end());
        for (Splat& s : splats) s.value = s.value * float(allocation->lightTracingWeight());
        if (!isBlack(cameraSum)) splats.push_back({at.film, cameraSum * at.cameraWeight});
      } else {
        pt.sample(at.film, sampler, &splats);
        for (Splat& s : splats) s.value = s.value * at.cameraWeight;
      }
    } else {
      Vec2f p;
      if (spec.budget >= 0) {
        int64_t pixel = k % pixels;
        p = Vec2f(float(pixel % camera.width()) + rng.nextFloat(),
                  float(pixel / camera.width()) + rng.nextFloat());
      } else {
        p = Vec2f(rng.nextFloat() * camera.width(), rng.nextFloat() * camera.height());
      }
      p.x = std::min(p.x, std::nextafter(float(camera.width()), 0.0f));
      p.y = std::min(p.y, std::nextafter(float(camera.height()), 0.0f));
      if (spec.algorithm == Algorithm::PathTracing)
        pt.sample(p, sampler, &splats);
      else
        bdpt.sample(p, sampler, &splats);
    }
    for (const Splat& s : splats) {
      if (flusher.check(s.value)) flusher.film().add(s.film, s.value);
    }
    const int64_t doneAfter = flusher.done() + 1;
    if (!flusher.countMutation(pt.rays() + bdpt.rays(),
                               [&] { return std::to_string(doneAfter); })) {
      return;
    }
  }
}

}  // namespace

RenderJob::RenderJob(std::shared_ptr<const Scene> scene, RenderSettings settings, std::string jobId)
    : scene_(std::move(scene)), settings_(std::move(settings)), jobId_(std::move(jobId)) {
  std::string problem = settings_.validate();
  if (!problem.empty()) throw std::invalid_argument(problem);
  const PixelAllocation* allocation = settings_.pixelAllocation.get();
  if (allocation && (allocation->width() != width() || allocation->height() != height())) {
    throw std::invalid_argument("the pixel allocation is for a film of " +
                                std::to_string(allocation->width()) + "x" +
                                std::to_string(allocation->height()) + ", the scene's is " +
                                std::to_string(width()) + "x" + std::to_string(height()));
  }
}

RenderJob::~RenderJob() = default;

int RenderJob::width() const {
  return scene_->camera().width();
}
int RenderJob::height() const {
  return scene_->camera().height();
}

int64_t RenderJob::plannedWork() const {
  if (settings_.timeBudgetSeconds > 0) return -1;
  const int64_t pixels = int64_t(width()) * height();
  return pixels * (isMarkovChain(settings_.algorithm) ? settings_.mutationsPerPixel
                                                      : settings_.samplesPerPixel);
}

static int resolvedMaxDepth(const RenderSettings& s, const Scene& scene) {
  if (s.maxDepth != 0) return s.maxDepth;
  return scene.maxDepth() == 0 ? -1 : scene.maxDepth();
}

BootstrapResult RenderJob::bootstrap(const ProgressCallback& progress) const {
  BootstrapResult result;
  if (!needsBootstrap(settings_.algorithm)) return result;
  auto start = std::chrono::steady_clock::now();
  const int64_t pixels = int64_t(width()) * height();
  if (scene_->lights().empty()) {
    throw std::runtime_error("no light reaches the camera: the scene has no emitters");
  }
  const int maxDepth = resolvedMaxDepth(settings_, *scene_);
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const int64_t work = plannedWork();
  BootstrapRequest request;
  request.algorithm = settings_.algorithm;
  request.fixedCount = settings_.bootstrapSamples;
  request.plannedWork = work;
  request.pixels = pixels;
  request.timeBudgetSeconds = settings_.timeBudgetSeconds;
  SizedCandidates sized;
  if (!drawSizedCandidates(
          candidateEvaluator(*scene_, settings_.algorithm, maxDepth, settings_.seed), request,
          &sized, [&](double f) { return !progress || progress(Progress{f}); })) {
    throw std::runtime_error("bootstrap cancelled");
  }
  const BootstrapCandidates& c = sized.candidates;
  const int64_t count = int64_t(c.contributions.size());
  result.pilotCandidates = sized.pilot;
  result.abandonedConnections = c.abandoned;
  result.candidatesForTime = sized.size.forTime;
  result.candidatesForError = sized.size.forError;
  if (!(c.mean > 0)) {
    if (settings_.algorithm == Algorithm::MLT && SeenEmission::separates(*scene_)) {
      throw std::runtime_error(
          "no light reaches the camera but from the lights it sees directly: none of " +
          std::to_string(count) +
          " bidirectional candidate paths carries other light, and mlt's chains leave those to "
          "its own sampler (use pt)");
    }
    throw std::runtime_error("no light reaches the camera: none of " + std::to_string(count) +
                             " bidirectional candidate paths carries light");
  }
  result.normalization = c.mean;
  result.normalizationStdError = c.stdError;
  result.candidates = count;
  result.nonZeroCandidates = c.nonZero;
  if (settings_.algorithm == Algorithm::ERPT) {  // Z sets the deposit energy; no seeds
    result.seconds = elapsed();
    return result;
  }
  const int chains = settings_.numChains > 0 ? settings_.numChains : kDefaultChains;
  std::vector<int64_t> picks = resampleSeeds(c.contributions, chains, settings_.seed);
  const std::vector<double>& contributions = c.contributions;
  const int64_t firstIndex = c.firstIndex;
  for (size_t c = 0; c < picks.size(); ++c) {
    const int64_t i = firstIndex + picks[c];  // the candidate's stream index
    if (settings_.algorithm == Algorithm::MLT) {
      // A path-space seed: one of the candidate's strategies, by its share of the luminance.
      Rng pick(settings_.seed, streamId(kPathSeedDomain, c));
      Path path;
      // A candidate whose light BDPT found through a film point within rounding of the film's
      // edge may have no strategy path that projects back onto the film: f(x) = 0 there, so
      // draw another (its share of Z is of the order of that rounding). In a medium, the
      // chain's own estimate of f(x) (ratio tracking, with the chain's numbers) may come out 0
      // however often the chain asks where transmittance is tiny: the chain could not start
      // there, so draw another too: the chain starts elsewhere, a start-up bias it forgets as it
      // mixes, as it forgets that its first estimate is drawn afresh.
      PathChain walker(*scene_, maxDepth, settings_.mutationMix, settings_.mediumSamples,
                       settings_.mediumMarchSteps);
      walker.setSeenEmissionApart(SeenEmission::separates(*scene_));
      auto chainStarts = [&] {
        Rng rng = mltChainRng(settings_.seed, uint32_t(c));
        return walker.start(path, rng);
      };
      int64_t candidate = i;
      for (int attempt = 0; !(candidatePath(*scene_, maxDepth, settings_.seed, candidate,
                                            pick.nextDouble(), &path) &&
                              chainStarts());
           ++attempt) {
        if (attempt == 64)
          throw std::runtime_error("bootstrap candidate " + std::to_string(candidate) +
                                   " and 64 others carry light but build no path a chain can "
                                   "start from: this host computes differently from itself");
        const uint64_t hi = pick.nextUint(), lo = pick.nextUint();  // in this order
        candidate = firstIndex + resampleSeeds(contributions, 1, (hi << 32) | lo)[0];
      }
      result.seedPaths.push_back(path.serialize());
      result.seedContributions.push_back(
          std::exp(path.contribution(*scene_, maxDepth, &kSeedEstimate).logLuminance));
      continue;
    }
    std::vector<float> u;
    double I = evaluateCandidate(*scene_, settings_.algorithm, maxDepth, settings_.seed, i, &u);
    result.seedSamples.push_back(std::move(u));
    result.seedContributions.push_back(I);
  }
  result.seconds = elapsed();
  return result;
}

std::vector<ChainSpec> RenderJob::planChains(const BootstrapResult& bootstrap) const {
  if (settings_.algorithm == Algorithm::ERPT) return planTiles(bootstrap);
  const bool mcmc = isMarkovChain(settings_.algorithm);
  const int chains = mcmc ? int(bootstrap.seedContributions.size())
                          : (settings_.numChains > 0 ? settings_.numChains : kDefaultChains);
  if (mcmc && chains == 0) throw std::runtime_error("the bootstrap produced no seed paths");
  const int64_t planned = plannedWork();
  const int64_t pixels = int64_t(width()) * height();
  const int groups =
      std::min(settings_.errorGroups > 0 ? settings_.errorGroups : kErrorGroups, chains);
  // Flush about once per image's worth of work per chain: large enough that a flush's cost
  // (the whole film) is small against the work it carries. Unless the user says otherwise.
  const int64_t interval = settings_.flushInterval > 0
                               ? settings_.flushInterval
                               : std::clamp<int64_t>(pixels, 4096, int64_t(1) << 20);
  std::vector<ChainSpec> specs;
  int64_t first = 0;
  for (int c = 0; c < chains; ++c) {
    ChainSpec s;
    s.jobId = jobId_;
    s.chainIndex = uint32_t(c);
    s.algorithm = settings_.algorithm;
    s.seed = settings_.seed;
    s.maxDepth = resolvedMaxDepth(settings_, *scene_);
    s.largeStepProbability = settings_.largeStepProbability;
    if (planned < 0) {
      s.budget = -1;
      s.firstSample = int64_t(c) * kUnboundedChainStride;
    } else {
      s.budget = planned / chains + (c < planned % chains ? 1 : 0);
      s.firstSample = first;
      first += s.budget;
    }
    if (mcmc) {
      if (settings_.algorithm == Algorithm::MLT) {
        s.seedPath = bootstrap.seedPaths[c];
        s.mutationMix = settings_.mutationMix;
        s.mediumSamples = settings_.mediumSamples;
        s.mediumMarchSteps = settings_.mediumMarchSteps;
        if (SeenEmission::separates(*scene_)) {
          s.seenEmissionEvery = kSeenEmissionEvery;
          s.seenEmissionScale = double(kSeenEmissionEvery) / bootstrap.normalization;
        }
      } else {
        s.seedSample = bootstrap.seedSamples[c];
        // Kelemen's b is the bootstrap's Z: the weights need a constant fixed before the chain
        // runs, and the image's scale (imageScale) is then that same Z, as the chains report
        // no large steps to pool into it (runPssmltChain).
        if (settings_.combineLargeSteps) {
          s.largeStepMis = bootstrap.normalization * double(settings_.largeStepProbability);
        }
      }
      s.seedContribution = bootstrap.seedContributions[c];
    } else {
      s.pixelAllocation = settings_.pixelAllocation;
    }
    s.flushInterval = s.budget > 0 ? std::min(interval, s.budget) : interval;
    s.errorGroup = uint32_t(int64_t(c) * groups / chains);  // contiguous: a worker's chains
                                                            // mostly share one
    specs.push_back(std::move(s));
  }
  return specs;
}

std::vector<ChainSpec> RenderJob::planTiles(const BootstrapResult& bootstrap) const {
  if (!(bootstrap.normalization > 0)) throw std::runtime_error("ERPT needs the bootstrap's Z");
  // Tiles of 32 x 32 pixels (fewer at the borders), each a work unit: seconds of work for a
  // worker at 16 seeds per pixel, and enough of them to spread over many hosts.
  constexpr int kTile = 32;
  const int64_t spp = settings_.timeBudgetSeconds > 0 ? -1 : settings_.samplesPerPixel;
  // Each tile's passes are split among the error groups (whole passes, so that every group's
  // image covers the film evenly): one work unit per group and tile, group after group. The
  // seeds are those of the undivided tile (a seed's numbers follow its pixel and pass).
  const int asked = settings_.errorGroups > 0 ? settings_.errorGroups : kErrorGroups;
  const int groups = int(spp < 0 ? asked : std::min<int64_t>(asked, spp));
  std::vector<ChainSpec> specs;
  int64_t firstPass = 0;
  for (int g = 0; g < groups; ++g) {
    const int64_t groupPasses = spp < 0 ? -1 : spp / groups + (g < spp % groups ? 1 : 0);
    for (int y = 0; y < height(); y += kTile) {
      for (int x = 0; x < width(); x += kTile) {
        ChainSpec s;
        s.errorGroup = uint32_t(g);
        s.jobId = jobId_;
        s.chainIndex = uint32_t(specs.size());
        s.algorithm = Algorithm::ERPT;
        s.seed = settings_.seed;
        s.maxDepth = resolvedMaxDepth(settings_, *scene_);
        s.tileX = x;
        s.tileY = y;
        s.tileWidth = std::min(kTile, width() - x);
        s.tileHeight = std::min(kTile, height() - y);
        const int64_t tilePixels = int64_t(s.tileWidth) * s.tileHeight;
        s.budget = spp < 0 ? -1 : tilePixels * groupPasses;
        s.firstSample = spp < 0 ? 0 : tilePixels * firstPass;
        // Flush every few thousand seeds (or what the user asked for), in whole passes over the
        // tile.
        const int64_t passes =
            settings_.flushInterval > 0
                ? std::max<int64_t>(1, (settings_.flushInterval + tilePixels - 1) / tilePixels)
                : std::max<int64_t>(1, 4096 / tilePixels);
        s.flushInterval =
            s.budget > 0 ? std::min(passes * tilePixels, s.budget) : passes * tilePixels;
        s.erptChains = settings_.erptChains;
        s.erptLength = settings_.erptLength;
        s.erptDeposit = bootstrap.normalization / (settings_.erptChains * settings_.erptLength);
        s.mediumSamples = settings_.mediumSamples;
        s.mediumMarchSteps = settings_.mediumMarchSteps;
        specs.push_back(std::move(s));
      }
    }
    firstPass += std::max<int64_t>(groupPasses, 0);
  }
  return specs;
}

double RenderJob::imageScale(const BootstrapResult& bootstrap, int64_t workDone) const {
  return imageScale(bootstrap, workDone, LargeStepSums());
}

double RenderJob::imageScale(const BootstrapResult& bootstrap, int64_t workDone,
                             const LargeStepSums& largeSteps) const {
  if (workDone <= 0) return 0;
  if (isMarkovChain(settings_.algorithm))
    return bootstrap.normalizationWith(largeSteps).value / double(workDone);
  return 1.0 / double(workDone);
}

void RenderJob::runChain(const ChainSpec& spec, const std::function<bool(ChainFlush&&)>& onFlush,
                         const std::atomic<bool>* cancel) const {
  if (spec.algorithm == Algorithm::MLT)
    runMltChain(*scene_, spec, onFlush, cancel);
  else if (spec.algorithm == Algorithm::ERPT)
    runErptTile(*scene_, spec, onFlush, cancel);
  else if (isPrimarySampleSpace(spec.algorithm))
    runPssmltChain(*scene_, spec, onFlush, cancel);
  else
    runSampleChain(*scene_, spec, onFlush, cancel);
}

template <class Sum>
void RenderJob::resolveFilmRows(const std::vector<Sum>& sums, double scale, int y0, int y1,
                                float* out) const {
  // Every estimator splats into pixel j with its filter h_j, so pixel j's expectation is the
  // integral of h_j L over the film. Dividing by the filter's mass on the film makes border
  // pixels the filter-weighted average that renderers report (no dark rim).
  const int w = width();
  const PixelFilter filter = PixelFilter::of(scene_->description().camera);
  std::vector<double> massX(static_cast<size_t>(w));
  for (int x = 0; x < w; ++x) massX[size_t(x)] = pixelFilterMassInside(filter, x, w);
  for (int y = y0; y < y1; ++y) {
    const double wy = pixelFilterMassInside(filter, y, height());
    for (int x = 0; x < w; ++x) {
      const double mass = wy * massX[size_t(x)];
      const size_t i = (size_t(y) * w + x) * 3;
      float* o = out + (size_t(y - y0) * w + x) * 3;
      for (int c = 0; c < 3; ++c) o[c] = float(double(sums[i + c]) * scale / mass);
    }
  }
}

Image RenderJob::resolve(const std::vector<double>& sums, double scale) const {
  Image image(width(), height());
  if (sums.size() >= image.rgb.size()) resolveFilmRows(sums, scale, 0, height(), image.rgb.data());
  return image;
}

void RenderJob::checkRows(size_t sums, int y0, int y1) const {
  if (sums < size_t(width()) * size_t(height()) * 3 || y0 < 0 || y1 > height() || y0 > y1)
    throw std::invalid_argument("rows " + std::to_string(y0) + " to " + std::to_string(y1) +
                                " of a film of " + std::to_string(sums) + " sums, not of " +
                                std::to_string(width()) + "x" + std::to_string(height()));
}

void RenderJob::resolveRows(const std::vector<double>& sums, double scale, int y0, int y1,
                            float* out) const {
  checkRows(sums.size(), y0, y1);
  resolveFilmRows(sums, scale, y0, y1, out);
}

void RenderJob::resolveRows(const std::vector<float>& sums, double scale, int y0, int y1,
                            float* out) const {
  checkRows(sums.size(), y0, y1);
  resolveFilmRows(sums, scale, y0, y1, out);
}

ImageMetadata RenderJob::metadata(const BootstrapResult& bootstrap, int64_t workDone,
                                  double seconds, const LargeStepSums& largeSteps) const {
  ImageMetadata m;
  m["farm:algorithm"] = algorithmName(settings_.algorithm);
  m["farm:scene"] = scene_->description().sourcePath;
  m["farm:seed"] = std::to_string(settings_.seed);
  m["farm:maxDepth"] = std::to_string(resolvedMaxDepth(settings_, *scene_));
  m["farm:shadingNormals"] = scene_->strictNormals() ? "strict" : "lax";
  m["farm:renderSeconds"] = formatDouble(seconds);
  const double pixels = double(width()) * height();
  if (isMarkovChain(settings_.algorithm)) {
    m["farm:mutations"] = std::to_string(workDone);
    m["farm:mutationsPerPixel"] = formatDouble(workDone / pixels);
    const Normalization z = bootstrap.normalizationWith(largeSteps);
    m["farm:normalization"] = formatDouble(z.value);
    m["farm:normalizationStdError"] = formatDouble(z.stdError);
    m["farm:bootstrapCandidates"] = std::to_string(bootstrap.candidates);
    if (largeSteps.count > 0) m["farm:normalizationLargeSteps"] = std::to_string(largeSteps.count);
    m["farm:bootstrapSeconds"] = formatDouble(bootstrap.seconds);
    if (settings_.algorithm == Algorithm::MLT) {
      m["farm:mutationMix"] = formatMutationMix(settings_.mutationMix);
    } else {
      m["farm:largeStepProbability"] = formatDouble(settings_.largeStepProbability);
      if (settings_.combineLargeSteps) m["farm:combineLargeSteps"] = "1";
    }
  } else {
    m["farm:samples"] = std::to_string(workDone);
    m["farm:samplesPerPixel"] = formatDouble(workDone / pixels);
    if (const PixelAllocation* a = settings_.pixelAllocation.get()) {
      size_t bidirectional = 0;
      for (uint8_t b : a->bidirectional()) bidirectional += b;
      const auto [lo, hi] = std::minmax_element(a->density().begin(), a->density().end());
      m["farm:pixelAllocation"] = std::to_string(a->cellsX()) + "x" + std::to_string(a->cellsY()) +
                                  " cells of " + std::to_string(a->cellSize()) + " pixels, " +
                                  std::to_string(bidirectional) + " bidirectional, densities " +
                                  formatDouble(*lo) + " to " + formatDouble(*hi);
    }
  }
  const bool pathSpace =
      settings_.algorithm == Algorithm::MLT || settings_.algorithm == Algorithm::ERPT;
  if (pathSpace && scene_->hasMedia()) {
    m["farm:mediumTransmittance"] =
        settings_.mediumMarchSteps > 0
            ? "marched, " + std::to_string(settings_.mediumMarchSteps) + " steps"
            : "ratio tracking, mean of " + std::to_string(settings_.mediumSamples);
  }
  if (settings_.algorithm == Algorithm::ERPT) {
    m["farm:normalization"] = formatDouble(bootstrap.normalization);
    m["farm:erptChainsPerSeed"] = formatDouble(settings_.erptChains);
    m["farm:erptChainLength"] = std::to_string(settings_.erptLength);
  }
  return m;
}

std::shared_ptr<Scene> loadScene(const std::string& path, const RenderSettings& settings) {
  SceneDescription desc = loadSceneDescription(path);
  // With auto the plan picks among the algorithms that can render it.
  const std::string refusal =
      settings.autoAlgorithm ? "" : algorithmRefusal(desc, settings.algorithm);
  if (!refusal.empty()) throw SceneLoadError(path, 0, refusal);
  if (settings.width > 0 || settings.height > 0) {
    applyFilmOverride(desc, settings.width, settings.height);
  }
  if (settings.shadingNormals != ShadingNormals::Scene)
    desc.strictNormals = settings.shadingNormals == ShadingNormals::Strict;
  return std::make_shared<Scene>(std::move(desc));
}

}  // namespace farm
