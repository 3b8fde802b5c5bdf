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

// Each chain group's film as summed (before resolve) and its samples.
struct GroupFilms {
  std::vector<std::vector<double>> sums;
  std::vector<int64_t> work;
};

// *image: the candidate's image, for the cross estimate (runPilot); *groupImages, when given,
// each chain group's (for a pixel allocation); *films, when given, their films and counts.
// `groups`: its chain groups (at least 2, at most kPilotMaxChains).
PilotFigure pilotOne(std::shared_ptr<const Scene> scene, RenderSettings settings, double seconds,
                     const std::function<bool()>& keepGoing, Image* image,
                     std::vector<Image>* groupImages = nullptr, GroupFilms* films = nullptr,
                     int groups = kPilotGroups) {
  PilotFigure figure;
  figure.algorithm = settings.algorithm;
  settings.autoAlgorithm = false;
  settings.pilot = false;
  settings.timeBudgetSeconds = seconds;
  settings.untilError = 0;
  groups = std::clamp(groups, 2, kPilotMaxChains);
  settings.errorGroups = groups;
  settings.numChains = std::clamp(settings.numChains > 0 ? settings.numChains : kPilotMaxChains,
                                  groups, kPilotMaxChains);
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
    if (films) {
      films->sums = std::move(sums);
      films->work = std::move(work);
    }
  } catch (const std::exception& e) {
    figure.estimatedRelMse = -1;
    figure.score = -1;
    figure.failure = e.what();
  }
  return figure;
}

// The allocation pilot's groups from `first` on, as the job's samples to keep, if
// pooledErrorRatio says they lower its error at the concentration of an allocation made from
// the groups before `first` alone (so that the decision does not select the kept samples by
// their own values); the job's count n_j at the pilot's rate over the rest of the budget.
void keepPilotSamples(GroupFilms& films, size_t first, double concentration,
                      const RenderSettings& settings, const PilotFigure& figure,
                      PilotSamples* samples, std::string* why) {
  // *samples is empty: allocationPilot cleared it.
  int64_t all = 0, kept = 0;
  for (size_t g = 0; g < films.work.size(); ++g) {
    all += films.work[g];
    if (g >= first) kept += films.work[g];
  }
  const double rest = settings.timeBudgetSeconds - figure.bootstrapSeconds - figure.seconds;
  const double jobSamples = figure.seconds > 0 ? double(all) / figure.seconds * rest : 0;
  const double np = double(kept), nj = std::max(jobSamples, 0.0);
  const double ratio = pooledErrorRatio(np, nj, concentration);
  char text[200];
  if (kept <= 0 || !(ratio < 1)) {
    std::snprintf(text, sizeof text,
                  "; its samples stay out of the image (beside the job's %.3g allocated ones they "
                  "would leave %.2f times the error)",
                  nj, ratio);
    *why += text;
    return;
  }
  const size_t values = films.sums.empty() ? 0 : films.sums.front().size();
  samples->sums.assign(values, 0.0);
  for (size_t g = first; g < films.sums.size(); ++g) {
    for (size_t k = 0; k < values; ++k) samples->sums[k] += films.sums[g][k];
    // Float, as the aggregator keeps its groups' films (splat_aggregator.h).
    samples->groupSums.emplace_back(films.sums[g].begin(), films.sums[g].end());
    std::vector<double>().swap(films.sums[g]);
    samples->groupWork.push_back(films.work[g]);
  }
  samples->work = kept;
  samples->seed = settings.seed;
  std::snprintf(text, sizeof text,
                "; half of its samples (%lld) join the image (beside the job's %.3g allocated "
                "ones, %.2f times the error of the job's alone)",
                (long long)kept, nj, ratio);
  *why += text;
}

}  // namespace

double pooledErrorRatio(double pilotSamples, double jobSamples, double concentration) {
  const double n = pilotSamples + jobSamples;
  return n > 0 ? jobSamples * (pilotSamples * concentration + jobSamples) / (n * n) : 1.0;
}

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
                                                       std::string* why, PilotSamples* samples) {
  if (samples) *samples = PilotSamples();
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
  GroupFilms films;
  // Twice the job's group count. All of them place the samples; the second half is what the
  // job may keep (PilotSamples), one group to each of the job's (SplatAggregator::addPrior), so
  // that every group of the job mixes the pilot's samples and the chains' alike. The pooled
  // image (S_p + S_j) / (n_p + n_j) is unbiased for any allocation, the one its samples helped
  // make too; a decision to keep them made from their own values would not be (kept where
  // they happened to look even), so it is made from the first half.
  const int jobGroups = std::max(settings.errorGroups > 0 ? settings.errorGroups : kErrorGroups, 2);
  const int pilotGroups = std::min(2 * jobGroups, kPilotMaxChains);
  const PilotFigure figure = pilotOne(scene, settings, seconds, keepGoing, &image, &groups,
                                      samples ? &films : nullptr, pilotGroups);
  if (figure.score < 0 || groups.size() < 4) {
    *why = "no pixel allocation: its pilot failed (" + figure.failure + ")";
    return nullptr;
  }
  const bool bidirectional = settings.algorithm == Algorithm::Bidirectional;
  auto allocation =
      std::make_shared<const PixelAllocation>(PixelAllocation::byError(groups, bidirectional));
  const auto [lo, hi] =
      std::minmax_element(allocation->density().begin(), allocation->density().end());
  char text[320];
  std::snprintf(text, sizeof text,
                "a pilot of %.1f s placed the samples by its error (densities %.2g to %.2g, "
                "%.2g times less error than uniform sampling where the error goes as the density "
                "squared)",
                figure.seconds, double(*lo), double(*hi), allocation->concentration());
  *why = text;
  if (samples) {
    // Whether to keep the second half rests on the first half's allocation alone.
    const size_t half = groups.size() / 2;
    groups.resize(half);
    const double concentration = PixelAllocation::byError(groups, bidirectional).concentration();
    keepPilotSamples(films, half, concentration, settings, figure, samples, why);
  }
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
                   const std::function<bool()>& keepGoing, PilotSamples* pilotSamples) {
  if (pilotSamples) *pilotSamples = PilotSamples();
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
        settings->pixelAllocation =
            allocationPilot(scene, *settings, seconds, keepGoing, &why, pilotSamples);
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
