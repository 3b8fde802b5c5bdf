#include "common/render/algorithm_pilot.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "common/film/batch_means.h"
#include "common/film/cross_estimate.h"
#include "common/render/render_job.h"
#include "common/scene/scene.h"

namespace farm {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// The pilot's chains are the job's (its --chains, 64 by default, at most kPilotMaxChains) in
// four groups, as the job's would be: a Markov chain's early error is mostly how much of the
// image its chains have covered, which the chain count sets. Each runs on a thread of its own,
// so that every chain gets the same share of the machine however few cores it has (a pool
// would run the first chains to the deadline and the rest not at all).
constexpr int kPilotGroups = 4;
constexpr int kPilotMaxChains = 64;

// *image: the candidate's image, for the cross estimate (runPilot); *groupImages, when given,
// each chain group's (for a pixel allocation).
PilotFigure pilotOne(std::shared_ptr<const Scene> scene, RenderSettings settings, double seconds,
                     const std::function<bool()>& keepGoing, Image* image,
                     std::vector<Image>* groupImages = nullptr) {
  PilotFigure figure;
  figure.algorithm = settings.algorithm;
  settings.autoAlgorithm = false;
  settings.pilot = false;
  settings.timeBudgetSeconds = seconds;
  settings.untilError = 0;
  settings.errorGroups = kPilotGroups;
  settings.numChains = std::clamp(settings.numChains > 0 ? settings.numChains : kPilotMaxChains,
                                  kPilotGroups, kPilotMaxChains);
  settings.bootstrapSamples = 0;
  // Flush often: the deadline is looked at only between flushes.
  settings.flushInterval = 1024;
  const auto start = Clock::now();
  try {
    RenderJob job(scene, settings, "pilot");
    BootstrapResult bootstrap =
        job.bootstrap([&](const Progress&) { return !keepGoing || keepGoing(); });
    figure.bootstrapSeconds = since(start);
    std::vector<ChainSpec> specs = job.planChains(bootstrap);
    const size_t size = size_t(job.width()) * job.height() * 3;
    const int groups = kPilotGroups;  // planChains: min(errorGroups, chains) of them
    std::vector<std::vector<double>> sums(groups, std::vector<double>(size, 0.0));
    std::vector<int64_t> work(groups, 0);
    LargeStepSums largeSteps;
    std::mutex mutex;
    std::atomic<bool> stop{false};
    std::string failure;
    const auto renderStart = Clock::now();
    std::vector<std::thread> threads;
    for (const ChainSpec& spec : specs) {
      threads.emplace_back([&, spec] {
        try {
          job.runChain(spec, [&](ChainFlush&& f) {
            {
              std::lock_guard<std::mutex> lock(mutex);
              std::vector<double>& s = sums[spec.errorGroup % groups];
              for (size_t k = 0; k < size && k < f.splats.size(); ++k) s[k] += f.splats[k];
              work[spec.errorGroup % groups] += f.mutations;
              largeSteps += f.largeSteps;
            }
            if (since(start) >= seconds || (keepGoing && !keepGoing())) stop = true;
            return !stop.load();
          });
        } catch (const std::exception& e) {
          std::lock_guard<std::mutex> lock(mutex);
          if (failure.empty()) failure = e.what();
          stop = true;
        }
      });
    }
    for (std::thread& t : threads) t.join();
    figure.seconds = since(renderStart);
    if (!failure.empty()) throw std::runtime_error(failure);
    if (keepGoing && !keepGoing()) throw std::runtime_error("cancelled");
    std::vector<double> total(size, 0.0);
    int64_t totalWork = 0;
    std::vector<Image> images;
    std::vector<double> groupWork;
    for (int g = 0; g < groups; ++g) {
      if (work[g] <= 0) throw std::runtime_error("a chain group did no work in the pilot");
      for (size_t k = 0; k < size; ++k) total[k] += sums[g][k];
      totalWork += work[g];
      images.push_back(job.resolve(sums[g], job.imageScale(bootstrap, work[g], largeSteps)));
      groupWork.push_back(double(work[g]));
    }
    *image = job.resolve(total, job.imageScale(bootstrap, totalWork, largeSteps));
    const double zRel = bootstrap.normalizationRelativeVariance(largeSteps);
    ErrorEstimate estimate;
    std::string error;
    if (!estimateError(images, groupWork, *image, zRel, &estimate, &error))
      throw std::runtime_error(error);
    figure.estimatedRelMse = estimate.relMse;
    figure.score = estimate.relMse * figure.seconds;
    if (groupImages) *groupImages = std::move(images);
  } catch (const std::exception& e) {
    figure.estimatedRelMse = -1;
    figure.score = -1;
    figure.failure = e.what();
  }
  return figure;
}

}  // namespace

double pilotSecondsEach(const RenderSettings& settings, size_t candidates) {
  if (candidates == 0) return 0;
  const double each = settings.timeBudgetSeconds > 0
                          ? kPilotShare * settings.timeBudgetSeconds / double(candidates)
                          : kPilotSecondsWithoutBudget;
  return each < kPilotMinSeconds ? 0.0 : std::min(each, kPilotMaxSeconds);
}

std::vector<PilotFigure> runPilot(std::shared_ptr<const Scene> scene,
                                  const RenderSettings& settings,
                                  const std::vector<Algorithm>& candidates, double seconds,
                                  const std::function<bool()>& keepGoing) {
  std::vector<PilotFigure> figures;
  std::vector<Image> images;
  for (Algorithm a : candidates) {
    if (keepGoing && !keepGoing()) break;
    RenderSettings s = settings;
    s.algorithm = a;
    images.emplace_back();
    figures.push_back(pilotOne(scene, s, seconds, keepGoing, &images.back()));
  }
  // Where three or more rendered, each is also judged by how far its image is from the others'
  // (common/film/cross_estimate.h): its own groups agree on light they have all missed, the
  // others' images do not. The score takes the larger of the two estimates.
  std::vector<const Image*> rendered;
  std::vector<PilotFigure*> renderedFigures;
  for (size_t i = 0; i < figures.size(); ++i) {
    if (figures[i].score < 0) continue;
    rendered.push_back(&images[i]);
    renderedFigures.push_back(&figures[i]);
  }
  const std::vector<double> cross = crossEstimates(rendered);
  for (size_t i = 0; i < cross.size(); ++i) {
    PilotFigure& f = *renderedFigures[i];
    f.crossRelMse = cross[i];
    f.score = std::max(f.estimatedRelMse, f.crossRelMse) * f.seconds;
  }
  std::stable_sort(figures.begin(), figures.end(), [](const PilotFigure& a, const PilotFigure& b) {
    const bool aOk = a.score >= 0, bOk = b.score >= 0;
    if (aOk != bOk) return aOk;
    return aOk && a.score < b.score;
  });
  return figures;
}

double allocationPilotSeconds(const RenderSettings& settings) {
  if (settings.timeBudgetSeconds <= 0) return 0;
  const double seconds = kAllocationShare * settings.timeBudgetSeconds;
  return seconds < kAllocationMinSeconds ? 0.0 : std::min(seconds, kPilotMaxSeconds);
}

std::shared_ptr<const PixelAllocation> allocationPilot(std::shared_ptr<const Scene> scene,
                                                       RenderSettings settings, double seconds,
                                                       const std::function<bool()>& keepGoing,
                                                       std::string* why) {
  if (settings.algorithm != Algorithm::PathTracing &&
      settings.algorithm != Algorithm::Bidirectional) {
    throw std::invalid_argument("a pixel allocation places independent samples: pt or bdpt");
  }
  // Other random numbers than the job's: sample k of the job is stream (seed, k), and a
  // pilot of the same seed would be the job's first samples, its densities following their noise.
  settings.seed = settings.seed ^ kAllocationSeedSalt;
  settings.pixelAllocation.reset();
  Image image;
  std::vector<Image> groups;
  const PilotFigure figure = pilotOne(scene, settings, seconds, keepGoing, &image, &groups);
  if (figure.score < 0 || groups.size() < 2) {
    *why = "no pixel allocation: its pilot failed (" + figure.failure + ")";
    return nullptr;
  }
  auto allocation = std::make_shared<const PixelAllocation>(
      PixelAllocation::byError(groups, settings.algorithm == Algorithm::Bidirectional));
  const auto [lo, hi] =
      std::minmax_element(allocation->density().begin(), allocation->density().end());
  char text[160];
  std::snprintf(text, sizeof text,
                "a pilot of %.1f s placed the samples by its error (densities %.2g to %.2g)",
                figure.seconds, double(*lo), double(*hi));
  *why = text;
  return allocation;
}

Algorithm pilotPick(Algorithm first, const std::vector<PilotFigure>& figures) {
  double firstScore = -1;
  for (const PilotFigure& f : figures)
    if (f.algorithm == first) firstScore = f.score;
  if (figures.empty() || figures.front().score < 0) return first;
  const PilotFigure& best = figures.front();
  return firstScore < 0 || best.score * kPilotMargin < firstScore ? best.algorithm : first;
}

RenderPlan planJob(std::shared_ptr<const Scene> scene, RenderSettings* settings,
                   const std::function<bool()>& keepGoing) {
  const SceneAnalysis analysis = analyseScene(*scene);
  RenderPlan plan = planRender(analysis, settings->algorithm, settings->autoAlgorithm,
                               settings->mutationMix, settings->numChains);
  if (settings->autoAlgorithm) {
    if (plan.shortlist.empty())
      throw std::runtime_error("no algorithm of this build can render this scene");
    if (plan.shortlist.size() == 1) {
      // One candidate: nothing to rank.
    } else if (!settings->pilot) {
      plan.why += "; no pilot (--pilot runs one), so the first renders";
    } else if (const double seconds = pilotSecondsEach(*settings, plan.shortlist.size());
               seconds <= 0) {
      plan.why += "; no pilot: " + std::to_string(int(100 * kPilotShare)) + "% of the budget " +
                  "gives each candidate under " + std::to_string(kPilotMinSeconds).substr(0, 4) +
                  " s, so the first renders";
    } else {
      RenderSettings pilot = *settings;
      pilot.mutationMix = plan.mutationMix;
      plan.pilot = runPilot(scene, pilot, plan.shortlist, seconds, keepGoing);
      if (keepGoing && !keepGoing()) throw std::runtime_error("cancelled");
      if (plan.pilot.empty() || plan.pilot.front().score < 0) {
        std::string why = plan.pilot.empty() ? "no candidate ran" : plan.pilot.front().failure;
        throw std::runtime_error("the pilot found no algorithm that renders this scene (" + why +
                                 ")");
      }
      const Algorithm first = plan.shortlist.front();
      const PilotFigure& best = plan.pilot.front();
      const Algorithm pick = pilotPick(first, plan.pilot);
      plan.why +=
          std::string("; the pilot: ") + algorithmName(pick) +
          (pick == first ? (best.algorithm == first
                                ? " scored best"
                                : std::string(" stays, ") + algorithmName(best.algorithm) +
                                      "'s score is not under half of its")
                         : " scored under half of " + std::string(algorithmName(first)) + "'s");
      plan.choose(pick);
    }
    settings->algorithm = plan.algorithm;
    settings->autoAlgorithm = false;
    settings->pilot = false;
    // Bidirectional path tracing's samples where its error is (docs/corpus.md, "Per-pixel
    // estimators and sample density"): with a time budget only, so that a job of counts keeps
    // its seed's image.
    if (settings->algorithm == Algorithm::Bidirectional && !settings->pixelAllocation) {
      if (const double seconds = allocationPilotSeconds(*settings); seconds > 0) {
        std::string why;
        settings->pixelAllocation = allocationPilot(scene, *settings, seconds, keepGoing, &why);
        if (keepGoing && !keepGoing()) throw std::runtime_error("cancelled");
        plan.why += "; " + why;
      }
    }
  }
  if (settings->ignorePlan) {
    plan.applied = false;
    plan.mutationMix = settings->mutationMix;
    plan.choose(plan.algorithm);
    plan.chains = 0;
  } else {
    settings->mutationMix = plan.mutationMix;
    if (plan.chains > 0) settings->numChains = plan.chains;
  }
  // The planned settings name the count the job runs, for its report and a restart.
  if (settings->numChains == 0) settings->numChains = kDefaultChains;
  return plan;
}

}  // namespace farm
