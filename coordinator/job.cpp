#include "coordinator/job.h"

#include <cmath>
#include <filesystem>
#include <set>

#include "common/film/batch_means.h"
#include "common/film/error_metrics.h"
#include "common/render/algorithm_pilot.h"
#include "common/scene/scene.h"
#include "coordinator/job_store.h"
#include "coordinator/progress_math.h"

namespace farm {
namespace fs = std::filesystem;

namespace {

// Loader messages name the file they read; for an uploaded bundle that is a path inside the
// coordinator's data directory, which means nothing to the person who submitted the scene.
std::string withoutPrefix(std::string message, const std::string& root) {
  if (root.empty()) return message;
  const std::string prefix = root + "/";
  for (size_t at = message.find(prefix); at != std::string::npos; at = message.find(prefix, at)) {
    message.erase(at, prefix.size());
  }
  return message;
}

// The reference image to measure the error against (none without a path); throws when it
// cannot be read or is not the film's size.
std::optional<Image> readReference(const std::string& path, const RenderJob& renderJob) {
  if (path.empty()) return std::nullopt;
  Image image;
  std::string error;
  if (!readExr(path, &image, &error)) {
    throw std::runtime_error("cannot read the reference image: " + error);
  }
  if (image.width != renderJob.width() || image.height != renderJob.height()) {
    throw std::runtime_error("the reference image is " + std::to_string(image.width) + "x" +
                             std::to_string(image.height) + " but the render is " +
                             std::to_string(renderJob.width()) + "x" +
                             std::to_string(renderJob.height()) +
                             " (set --width/--height to the reference's size)");
  }
  return image;
}

// The error groups' images and the job's image, resolved from the aggregator's films a band of
// rows at a time as the estimate reads them; each group's with its own work (Z pooled from all
// the chains, as the image's: batch_means.h counts Z's error once, not as spread).
class AggregatedFilms : public ErrorFilms {
 public:
  AggregatedFilms(const RenderJob& job, const BootstrapResult& bootstrap,
                  const SplatAggregator& sums)
      : job_(job), bootstrap_(bootstrap), sums_(sums) {}
  int width() const override { return job_.width(); }
  int height() const override { return job_.height(); }
  size_t groups() const override { return sums_.groups(); }
  void rows(size_t g, int y0, int y1, float* out) const override {
    if (g == sums_.groups()) {
      job_.resolveRows(sums_.sums(), scale(sums_.workDone()), y0, y1, out);
    } else {
      job_.resolveRows(sums_.groupSums(uint32_t(g)), scale(sums_.groupWork(uint32_t(g))), y0, y1,
                       out);
    }
  }

 private:
  double scale(int64_t work) const { return job_.imageScale(bootstrap_, work, sums_.largeSteps()); }
  const RenderJob& job_;
  const BootstrapResult& bootstrap_;
  const SplatAggregator& sums_;
};

}  // namespace

Job::Job(std::string id, JobSpec spec, SteadyClock::duration leaseDuration, std::string outputDir,
         Log log, std::function<void()> workFreed, JobStore* store, uint64_t firstEpoch,
         int maxChainFailures)
    : id_(std::move(id)),
      spec_(std::move(spec)),
      settings_(spec_.settings),
      leaseDuration_(leaseDuration),
      outputDir_(std::move(outputDir)),
      submitted_(SteadyClock::now()),
      log_(std::move(log)),
      workFreed_(std::move(workFreed)),
      store_(store),
      firstEpoch_(firstEpoch),
      maxChainFailures_(std::max(1, maxChainFailures)) {}

Job::~Job() {
  cancelRequested_ = true;
  if (preparer_.joinable()) preparer_.join();
}

Algorithm Job::algorithm() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return settings_.algorithm;
}

void Job::start() {
  preparer_ = std::thread([this] { prepare(); });
}

JobPhase Job::phase() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return phase_;
}

double Job::secondsSince(SteadyClock::time_point t, SteadyClock::time_point now) const {
  return std::chrono::duration<double>(now - t).count();
}

void Job::prepare() {
  auto setPhase = [this](JobPhase phase) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (isTerminal(phase_)) return false;
    phase_ = phase;
    return true;
  };
  try {
    if (!setPhase(JobPhase::kLoadingScene)) return;
    const auto loadStart = SteadyClock::now();
    std::shared_ptr<Scene> scene = loadScene(spec_.scenePath, spec_.settings);
    for (const std::string& w : scene->description().warnings) log("scene warning: " + w);
    // The plan (and with --algorithm auto --pilot its pilot) settles the settings the chains run
    // with.
    RenderSettings settings = spec_.settings;
    if (settings.autoAlgorithm && settings.pilot)
      log("planning: a pilot ranks the plan's candidates");
    PilotSamples pilotSamples;
    const RenderPlan plan = planJob(
        scene, &settings, [this] { return !cancelRequested_.load(); }, &pilotSamples);
    std::vector<std::string> planLines = plan.describe();
    for (const std::string& line : planLines) log("plan: " + line);
    auto renderJob = std::make_shared<RenderJob>(scene, settings, id_);
    std::optional<Image> reference = readReference(spec_.referencePath, *renderJob);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (isTerminal(phase_)) return;
      loadSeconds_ = secondsSince(loadStart, SteadyClock::now());
      warnings_ = scene->description().warnings;
      settings_ = settings;
      renderPlan_ = std::move(planLines);
      renderJob_ = renderJob;
      width_ = renderJob->width();
      height_ = renderJob->height();
      reference_ = std::move(reference);
      phase_ = JobPhase::kBootstrapping;
    }

    // The bootstrap runs without the lock: progress polls and cancellation must get through.
    BootstrapResult bootstrap =
        renderJob->bootstrap([this](const Progress&) { return !cancelRequested_.load(); });
    std::vector<ChainSpec> chains = renderJob->planChains(bootstrap);
    if (chains.empty()) throw std::runtime_error("the render plan has no chains");
    // Every seed now travels in its ChainSpec; the job keeps Z and its figures only.
    bootstrap.seedSamples = {};
    bootstrap.seedPaths = {};
    bootstrap.seedContributions = {};
    for (size_t i = 0; i < chains.size(); ++i) {
      if (chains[i].chainIndex != i) {
        throw std::runtime_error("internal error: chain " + std::to_string(i) +
                                 " of the plan carries index " +
                                 std::to_string(chains[i].chainIndex));
      }
    }

    std::lock_guard<std::mutex> lock(mutex_);
    if (isTerminal(phase_)) return;
    const uint32_t count = uint32_t(chains.size());
    if (store_) {
      // Rendering begins only once the plan is durable: a restart then resumes these chains
      // instead of bootstrapping again (with another Z) under flushes already accepted.
      JobPlan plan;
      plan.bootstrap = bootstrap;
      plan.chains = chains;
      plan.plannedWork = renderJob->plannedWork();
      plan.width = width_;
      plan.height = height_;
      plan.loadSeconds = loadSeconds_;
      plan.warnings = warnings_;
      plan.renderPlan = renderPlan_;
      plan.plannedSettings = settings_;
      Status saved = store_->savePlan(id_, plan, secondsSince(submitted_, SteadyClock::now()));
      if (!saved.isOk()) throw std::runtime_error(saved.message());
    }
    bootstrap_ = std::move(bootstrap);
    plannedWork_ = renderJob->plannedWork();
    aggregator_ = std::make_unique<SplatAggregator>(renderJob->width(), renderJob->height(),
                                                    errorGroupsOf(chains));
    scheduler_ = std::make_unique<ChainScheduler>(std::move(chains), leaseDuration_, firstEpoch_);
    if (pilotSamples.work > 0) {
      // The allocation pilot's samples are the image's first (algorithm_pilot.h, PilotSamples).
      // Durable at once as the job's first checkpoint: a restart reads them with their counts
      // from it, or, had the coordinator gone before it, neither (the chains' image alone,
      // unbiased too), never the one without the other or them twice.
      try {
        aggregator_->addPrior(pilotSamples);
        if (store_) {
          Status st = store_->checkpoint(id_, *aggregator_, scheduler_->snapshot());
          if (!st.isOk()) log("cannot checkpoint the pilot's samples: " + st.message());
        }
      } catch (const std::exception& e) {
        // addPrior changes nothing when it refuses: the chains' image alone, as before.
        log(std::string("the pilot's samples are left out: ") + e.what());
      }
      pilotSamples = PilotSamples();
    }
    renderStarted_ = SteadyClock::now();
    phase_ = JobPhase::kRendering;
    std::string z;
    if (needsBootstrap(settings_.algorithm)) {
      z = ", Z = " + std::to_string(bootstrap_.normalization) + " +- " +
          std::to_string(bootstrap_.normalizationStdError) + " from " +
          std::to_string(bootstrap_.candidates) + " candidates" +
          (bootstrap_.pilotCandidates > 0
               ? " after a pilot of " + std::to_string(bootstrap_.pilotCandidates)
               : std::string()) +
          " in " + std::to_string(bootstrap_.seconds) + " s";
      if (bootstrap_.candidatesForTime > 0 || bootstrap_.candidatesForError > 0) {
        z += " (the time share allows " + std::to_string(bootstrap_.candidatesForTime) +
             ", Z's error asks for " + std::to_string(bootstrap_.candidatesForError) + ")";
      }
    }
    log("rendering " + std::to_string(count) + " chains (" + std::to_string(width_) + "x" +
        std::to_string(height_) + ", " + algorithmName(settings_.algorithm) + z + ")");
    if (workFreed_) workFreed_();
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (isTerminal(phase_)) return;  // a cancelled bootstrap throws too
    failLocked(withoutPrefix(e.what(), spec_.bundleRoot));
  }
}

void Job::restore(StoredJob stored) {
  const SteadyClock::time_point now = SteadyClock::now();
  std::unique_lock<std::mutex> lock(mutex_);
  // The job's clock goes on from where it was last written: the time the coordinator was down
  // counts neither towards its elapsed time nor towards a time budget.
  submitted_ = now - std::chrono::duration_cast<SteadyClock::duration>(
                         std::chrono::duration<double>(std::max(0.0, stored.elapsedSeconds)));
  errorSeries_ = std::move(stored.errorSeries);
  error_ = stored.error;
  if (stored.plan) {
    bootstrap_ = stored.plan->bootstrap;
    plannedWork_ = stored.plan->plannedWork;
    width_ = stored.plan->width;
    height_ = stored.plan->height;
    loadSeconds_ = stored.plan->loadSeconds;
    warnings_ = stored.plan->warnings;
    renderPlan_ = stored.plan->renderPlan;
    if (stored.plan->plannedSettings) settings_ = *stored.plan->plannedSettings;
  }
  if (isTerminal(stored.phase)) {
    phase_ = stored.phase;
    endedAt_ = now;
    if (stored.checkpoint) {
      // An ended job's checkpoint holds its counts only (JobStore::setPhase).
      std::vector<uint32_t> groups =
          stored.plan ? errorGroupsOf(stored.plan->chains)
                      : std::vector<uint32_t>(stored.checkpoint->nextFlush.size(), 0);
      try {
        aggregator_ = std::make_unique<SplatAggregator>(0, 0, std::move(groups),
                                                        std::move(*stored.checkpoint));
      } catch (const std::exception& e) {
        log(std::string("its counts are unreadable: ") + e.what());
      }
    }
    if (phase_ == JobPhase::kDone) {
      const std::string path = (fs::path(outputDir_) / "image.exr").string();
      Image image;
      std::string error;
      if (readExr(path, &image, &error, &finalMetadata_)) {
        finalImage_ = std::move(image);
        imagePath_ = path;
      } else {
        phase_ = JobPhase::kFailed;
        error_ = "the final image is gone: " + error;
      }
    }
    return;
  }
  if (stored.phase != JobPhase::kRendering || !stored.plan) {
    lock.unlock();
    log("resubmitted after a restart (it had not started rendering)");
    start();
    return;
  }
  const JobPlan& plan = *stored.plan;
  const uint32_t count = uint32_t(plan.chains.size());
  try {
    aggregator_ =
        stored.checkpoint
            ? std::make_unique<SplatAggregator>(width_, height_, errorGroupsOf(plan.chains),
                                                std::move(*stored.checkpoint))
            : std::make_unique<SplatAggregator>(width_, height_, errorGroupsOf(plan.chains));
    scheduler_ = std::make_unique<ChainScheduler>(plan.chains, leaseDuration_, firstEpoch_);
    if (!stored.checkpointChains.empty()) scheduler_->restore(stored.checkpointChains);
  } catch (const std::exception& e) {
    failLocked(std::string("cannot resume after a restart: ") + e.what());
    return;
  }
  for (FlushBatch& batch : stored.tail) {
    std::string problem;
    if (aggregator_->addBatch(batch, &problem) != FlushOutcome::kAccepted) {
      failLocked("cannot resume after a restart: the recorded flushes do not follow each other (" +
                 problem + ")");
      return;
    }
    for (ChainFlush& flush : batch.entries) {
      scheduler_->recordFlush(flush.chainIndex, flush.flushIndex, flush.mutations,
                              std::move(flush.state), flush.finished, "", 0, now);
    }
  }
  if (!stored.tail.empty() && store_) {
    // Fold the replayed log now, so that restarts in a row never replay more than one interval.
    Status st = store_->checkpoint(id_, *aggregator_, scheduler_->snapshot());
    if (!st.isOk()) log("cannot checkpoint: " + st.message());
  }
  const double rendered = std::max(0.0, stored.elapsedSeconds - loadSeconds_ - bootstrap_.seconds);
  renderStarted_ = now - std::chrono::duration_cast<SteadyClock::duration>(
                             std::chrono::duration<double>(rendered));
  phase_ = JobPhase::kRendering;
  log("resumed after a restart: " + std::to_string(scheduler_->finishedCount()) + " of " +
      std::to_string(count) + " chains finished, " + std::to_string(aggregator_->workDone()) + " " +
      (isMarkovChain(settings_.algorithm) ? "mutations" : "samples") + " done (" +
      std::to_string(stored.tail.size()) + " flushes replayed after the checkpoint)");
  preparer_ = std::thread([this] { loadForRestore(); });
  if (workFreed_) workFreed_();
}

void Job::loadForRestore() {
  try {
    std::shared_ptr<Scene> scene = loadScene(spec_.scenePath, settings_);
    auto renderJob = std::make_shared<RenderJob>(scene, settings_, id_);
    std::optional<Image> reference = readReference(spec_.referencePath, *renderJob);
    std::lock_guard<std::mutex> lock(mutex_);
    if (isTerminal(phase_)) return;
    if (renderJob->width() != width_ || renderJob->height() != height_) {
      failLocked("the scene loads at " + std::to_string(renderJob->width()) + "x" +
                 std::to_string(renderJob->height()) + " after a restart, not " +
                 std::to_string(width_) + "x" + std::to_string(height_));
      return;
    }
    renderJob_ = std::move(renderJob);
    reference_ = std::move(reference);
    finishIfCompleteLocked(SteadyClock::now());
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (isTerminal(phase_)) return;
    failLocked("cannot load the scene again after a restart: " +
               withoutPrefix(e.what(), spec_.bundleRoot));
  }
}

void Job::failLocked(const std::string& message) {
  phase_ = JobPhase::kFailed;
  error_ = message.empty() ? "unknown error" : message;
  log("failed: " + error_);
  endedAt_ = SteadyClock::now();
  if (scheduler_) scheduler_->stop();
  recordEndLocked();
  endedSignal_.notify_all();
}

void Job::recordEndLocked() {
  if (!store_) return;
  const SplatAggregator::Snapshot counts =
      aggregator_ ? aggregator_->snapshot(false) : SplatAggregator::Snapshot();
  Status st = store_->setPhase(id_, phase_, error_, secondsSince(submitted_, *endedAt_),
                               aggregator_ ? &counts : nullptr);
  // The job has ended in memory whatever the disk says; a restart would redo its last part.
  if (!st.isOk()) log("cannot record its end: " + st.message());
}

void Job::countFailureLocked(const std::string& worker, uint32_t chain, const std::string& why) {
  if (worker.empty() || setAside_.count(worker)) return;
  const int failures = ++chainFailures_[worker][chain];
  if (failures < maxChainFailures_) return;
  const std::string reason = "worker " + worker + " set aside: chain " + std::to_string(chain) +
                             " failed on it " + std::to_string(failures) + " times (last: " + why +
                             ")";
  setAside_[worker] = reason;
  log(reason);
  std::set<std::string>& blamed = setAsideBy_[chain];
  blamed.insert(worker);
  if (int(blamed.size()) >= kWorkersToBlameAChain && !isTerminal(phase_)) {
    failLocked("chain " + std::to_string(chain) + " failed " + std::to_string(failures) +
               " times on each of " + std::to_string(blamed.size()) + " workers (last: " + why +
               "): the chain, not the workers, is at fault; the coordinator's log has each "
               "failure");
  }
}

void Job::checkpointLocked() {
  if (!store_) return;
  const uint64_t filmBytes = uint64_t(width_) * uint64_t(height_) * 3 * sizeof(double);
  if (tailBytes_ < store_->checkpointThreshold(filmBytes)) return;
  Status st = store_->checkpoint(id_, *aggregator_, scheduler_->snapshot());
  if (st.isOk()) {
    tailBytes_ = 0;
  } else {
    log("cannot checkpoint (the log keeps growing): " + st.message());
  }
}

std::vector<WorkerLease> Job::lease(const std::string& worker, int max,
                                    SteadyClock::time_point now) {
  std::vector<WorkerLease> out;
  std::lock_guard<std::mutex> lock(mutex_);
  if (phase_ != JobPhase::kRendering || setAside_.count(worker)) return out;
  enforceBudgetLocked(now);
  for (ChainLease& lease : scheduler_->lease(worker, max, now)) {
    WorkerLease w;
    w.jobId = id_;
    w.lease = std::move(lease);
    w.bundleHash = spec_.bundleHash;
    w.bundleScenePath = spec_.bundleScenePath;
    w.settings = settings_;
    out.push_back(std::move(w));
  }
  return out;
}

bool Job::renew(const std::string& worker, uint32_t chain, uint64_t epoch,
                SteadyClock::time_point now) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (phase_ != JobPhase::kRendering) return false;
  return scheduler_->renew(worker, chain, epoch, now);
}

void Job::tick(SteadyClock::time_point now) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (phase_ != JobPhase::kRendering) return;
  std::vector<std::pair<uint32_t, std::string>> holders;
  if (int expired = scheduler_->expireLeases(now, &holders)) {
    if (!scheduler_->stopping()) {
      for (const auto& [chain, holder] : holders) {
        countFailureLocked(holder, chain, "its lease expired without a flush or renewal");
      }
    }
    log(std::to_string(expired) + " lease(s) expired; " +
        (scheduler_->stopping() ? "those chains end there"
                                : "those chains resume from their last accepted flush"));
    if (!scheduler_->stopping() && workFreed_) workFreed_();
  }
  enforceBudgetLocked(now);
  finishIfCompleteLocked(now);
}

void Job::enforceBudgetLocked(SteadyClock::time_point now) {
  if (scheduler_->stopping()) return;
  const double budget = settings_.timeBudgetSeconds;
  if (budget > 0 && secondsSince(submitted_, now) >= budget) {
    scheduler_->stop();
    return;
  }
  // --until-error: the estimate (never the reference: a user's job has none) has reached it.
  const double target = settings_.untilError;
  if (target > 0 && !errorSeries_.empty() && errorSeries_.back().estimatedRelMse >= 0 &&
      errorSeries_.back().estimatedRelMse <= target) {
    log("the estimated relative MSE " + std::to_string(errorSeries_.back().estimatedRelMse) +
        " is within --until-error " + std::to_string(target) + ": stopping the chains");
    scheduler_->stop();
  }
}

void Job::recordErrorLocked(SteadyClock::time_point now, bool force) {
  if (!aggregator_ || !renderJob_) return;
  const uint32_t groups = aggregator_->groups();
  if (!reference_ && groups < 2) return;
  const int64_t work = aggregator_->workDone();
  if (work <= 0) return;
  if (!errorSeries_.empty() && errorSeries_.back().samples == work) return;
  // Each measurement resolves the whole film once a group (W*H work each): skip flushes while
  // the measurements have cost more than their share of the job's time so far (a tenth with a
  // reference, whose curve is what the user asked for; 3% for the estimate alone).
  const double share = reference_ ? 0.1 : 0.03;
  if (!force && metricsSeconds_ > share * secondsSince(submitted_, now)) return;
  const auto start = SteadyClock::now();
  ErrorSample sample;
  sample.elapsedSeconds = secondsSince(submitted_, now);
  sample.samples = work;
  if (reference_) {
    Image image = renderJob_->resolve(
        aggregator_->sums(), renderJob_->imageScale(bootstrap_, work, aggregator_->largeSteps()));
    ErrorMetrics metrics;
    if (compareImages(image, *reference_, &metrics, nullptr)) {
      sample.rmse = metrics.rmse;
      sample.relMse = metrics.relMse;
    }
  }
  // Batch means over the error groups, once every group has work to show, resolved from the
  // films a band of rows at a time (batch_means.h).
  std::vector<double> groupWork;
  for (uint32_t g = 0; g < groups && groups >= 2; ++g) {
    const int64_t w = aggregator_->groupWork(g);
    if (w <= 0) break;
    groupWork.push_back(double(w));
  }
  if (groupWork.size() == groups && groups >= 2) {
    const double zRel = bootstrap_.normalizationRelativeVariance(aggregator_->largeSteps());
    ErrorEstimate estimate;
    if (estimateError(AggregatedFilms(*renderJob_, bootstrap_, *aggregator_), groupWork, zRel,
                      &estimate, nullptr))
      sample.estimatedRelMse = estimate.relMse;
  }
  if (sample.relMse >= 0 || sample.estimatedRelMse >= 0) {
    errorSeries_.push_back(sample);
    if (store_) {
      Status st =
          store_->addErrorSample(id_, uint32_t(errorSeries_.size() - 1), errorSeries_.back());
      if (!st.isOk()) log(st.message());
    }
  }
  metricsSeconds_ += secondsSince(start, SteadyClock::now());
}

void Job::finishIfCompleteLocked(SteadyClock::time_point now) {
  if (phase_ != JobPhase::kRendering || !scheduler_->allFinished()) return;
  if (!renderJob_) return;  // restored, its scene still loading: loadForRestore() finishes it
  phase_ = JobPhase::kFinishing;
  try {
    const int64_t work = aggregator_->workDone();
    if (work - aggregator_->priorWork() <= 0) {
      failLocked("no chain reported any work before the job ended (time budget too short?)");
      return;
    }
    recordErrorLocked(now, true);
    const double seconds = secondsSince(submitted_, now);
    Image image = renderJob_->resolve(
        aggregator_->sums(), renderJob_->imageScale(bootstrap_, work, aggregator_->largeSteps()));
    ImageMetadata metadata =
        renderJob_->metadata(bootstrap_, work, seconds, aggregator_->largeSteps());
    metadata["farm:jobId"] = id_;
    if (const int64_t prior = aggregator_->priorWork(); prior > 0) {
      // farm:samples counts them too: they are in the image.
      metadata["farm:pilotSamples"] = std::to_string(prior);
      metadata["farm:pilotSeed"] = std::to_string(settings_.seed ^ kAllocationSeedSalt);
    }
    std::error_code ec;
    fs::create_directories(outputDir_, ec);
    const std::string path = (fs::path(outputDir_) / "image.exr").string();
    std::string error;
    if (!writeExr(path, image, metadata, &error)) {
      failLocked("cannot write the final image: " + error);
      return;
    }
    writePreview((fs::path(outputDir_) / "image.png").string(), image, &error);
    imagePath_ = path;
    finalImage_ = std::move(image);
    finalMetadata_ = std::move(metadata);
    phase_ = JobPhase::kDone;
    endedAt_ = now;
    recordEndLocked();
    renderJob_.reset();  // the scene is no longer needed here (workers may still hold theirs)
    log("done in " + std::to_string(seconds) + " s, " + std::to_string(work) + " " +
        (isMarkovChain(settings_.algorithm) ? "mutations" : "samples"));
    endedSignal_.notify_all();
  } catch (const std::exception& e) {
    failLocked(std::string("cannot resolve the final image: ") + e.what());
  }
}

JobPhase Job::cancel(bool record) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (isTerminal(phase_)) return phase_;
  cancelRequested_ = true;
  phase_ = JobPhase::kCancelled;
  log("cancelled");
  endedAt_ = SteadyClock::now();
  if (scheduler_) scheduler_->stop();
  if (record) recordEndLocked();
  endedSignal_.notify_all();
  return phase_;
}

JobProgress Job::progress(uint32_t errorSeriesFrom) const {
  std::lock_guard<std::mutex> lock(mutex_);
  JobProgress p;
  p.jobId = id_;
  p.name = spec_.name;
  p.phase = phase_;
  p.error = error_;
  p.settings = settings_;
  const SteadyClock::time_point now = endedAt_ ? *endedAt_ : SteadyClock::now();
  p.elapsedSeconds = secondsSince(submitted_, now);
  p.loadSeconds = loadSeconds_;
  p.warnings = warnings_;
  p.renderPlan = renderPlan_;
  for (const auto& [worker, why] : setAside_) p.setAside.push_back(why);
  p.bootstrapSeconds = bootstrap_.seconds;
  // Z as the image is scaled by it: the bootstrap's, with the large steps accepted so far.
  const Normalization z =
      bootstrap_.normalizationWith(aggregator_ ? aggregator_->largeSteps() : LargeStepSums());
  p.normalization = z.value;
  p.normalizationStdError = z.stdError;
  p.bootstrapCandidates = bootstrap_.candidates;
  p.abandonedConnections = bootstrap_.abandonedConnections;
  p.largeSteps = aggregator_ ? aggregator_->largeSteps().count : 0;
  p.plannedWork = plannedWork_;
  p.width = width_;
  p.height = height_;
  if (renderStarted_) p.renderSeconds = secondsSince(*renderStarted_, now);
  if (aggregator_) {
    p.workDone = aggregator_->workDone();
    p.pilotWork = aggregator_->priorWork();
    p.rejected = aggregator_->rejected();
    p.tallies = aggregator_->tallies();
    p.rays = aggregator_->rays();
    if (p.renderSeconds > 0) p.raysPerSecond = double(p.rays) / p.renderSeconds;
  }
  if (scheduler_) {
    p.chainsTotal = scheduler_->chainCount();
    p.chainsFinished = scheduler_->finishedCount();
    p.chainsLeased = scheduler_->leasedCount();
    p.activeWorkers = scheduler_->holderCount();
  }
  // The rate is the chains' own: the pilot's samples were taken before renderSeconds began.
  const ProgressEstimate estimate =
      estimateProgress(p.workDone - p.pilotWork, p.plannedWork, settings_.timeBudgetSeconds,
                       p.elapsedSeconds, p.renderSeconds);
  p.fraction = estimate.fraction;
  p.samplesPerSecond = estimate.samplesPerSecond;
  p.etaSeconds = estimate.etaSeconds;
  if (phase_ == JobPhase::kDone) {
    p.fraction = 1;
    p.etaSeconds = 0;
  } else if (phase_ != JobPhase::kRendering) {
    p.etaSeconds = -1;
    if (phase_ != JobPhase::kFinishing && isTerminal(phase_)) p.etaSeconds = 0;
  }
  p.hasReference = reference_.has_value() || !spec_.referencePath.empty();
  p.errorSeriesTotal = uint32_t(errorSeries_.size());
  for (size_t i = errorSeriesFrom; i < errorSeries_.size(); ++i) {
    p.errorSeries.push_back(errorSeries_[i]);
  }
  return p;
}

Status Job::notDoneStatusLocked() const {
  switch (phase_) {
    case JobPhase::kDone:
      return Status::ok();
    case JobPhase::kFailed:
      return Status::failedPrecondition("job " + id_ + " failed: " + error_);
    case JobPhase::kCancelled:
      return Status::failedPrecondition("job " + id_ + " was cancelled");
    default: {
      std::string done;
      if (aggregator_ && plannedWork_ > 0) {
        done = " (" + std::to_string(int(100.0 * double(aggregator_->workDone()) / plannedWork_)) +
               "% done)";
      }
      return Status::failedPrecondition("job " + id_ + " is still " + jobPhaseName(phase_) + done);
    }
  }
}

Status Job::imageFile(std::string* path) const {
  std::lock_guard<std::mutex> lock(mutex_);
  Status status = notDoneStatusLocked();
  if (status.isOk()) *path = imagePath_;
  return status;
}

Status Job::finalImage(Image* image, ImageMetadata* metadata) const {
  std::lock_guard<std::mutex> lock(mutex_);
  Status status = notDoneStatusLocked();
  if (!status.isOk()) return status;
  if (image) *image = *finalImage_;
  if (metadata) *metadata = finalMetadata_;
  return status;
}

Status Job::currentImage(Image* image) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finalImage_) {
    *image = *finalImage_;
    return Status::ok();
  }
  const int64_t work = aggregator_ ? aggregator_->workDone() : 0;
  if (!renderJob_ || work <= 0) {
    return Status::failedPrecondition("job " + id_ + " has no image yet (" + jobPhaseName(phase_) +
                                      ", no work accepted)");
  }
  *image = renderJob_->resolve(aggregator_->sums(),
                               renderJob_->imageScale(bootstrap_, work, aggregator_->largeSteps()));
  return Status::ok();
}

std::map<std::string, uint32_t> Job::leaseHolders() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return scheduler_ ? scheduler_->holders() : std::map<std::string, uint32_t>();
}

JobPhase Job::waitForEnd(SteadyClock::duration timeout) const {
  std::unique_lock<std::mutex> lock(mutex_);
  endedSignal_.wait_for(lock, timeout, [this] { return isTerminal(phase_); });
  return phase_;
}

std::shared_ptr<const RenderJob> Job::renderJob() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return renderJob_;
}

}  // namespace farm
