#pragma once
// One render job on the coordinator, through its lifecycle: submitted -> loading the scene ->
// bootstrapping (on a thread of its own) -> rendering (chains leased to workers, flushes summed)
// -> done; or failed (with the reason kept for status and fetch) or cancelled.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "common/film/image.h"
#include "common/render/job_phase.h"
#include "common/render/job_progress.h"
#include "common/render/render_job.h"
#include "coordinator/chain_scheduler.h"
#include "coordinator/splat_aggregator.h"
#include "coordinator/status.h"

namespace farm {

struct EncodedSplats;  // proto/splat_codec.h

// What a job renders and where its inputs are on the coordinator's disk.
struct JobSpec {
  RenderSettings settings;
  std::string scenePath;        // the file to load
  std::string referencePath;    // an EXR to measure the error against, or empty
  std::string name;             // for listings
  std::string bundleHash;       // what workers fetch; empty for embedded jobs (same process)
  std::string bundleScenePath;  // the scene inside the bundle
  std::string bundleRoot;       // stripped from loader messages so they name bundle paths
};

// A chain leased to a worker, with what the worker needs to load the scene.
struct WorkerLease {
  std::string jobId;
  ChainLease lease;
  std::string bundleHash, bundleScenePath;
  RenderSettings settings;
};

struct FlushAck {
  // kResend and kRefused answer entries of a batch that was not taken (Job::acceptBatch): the
  // first is sound and goes again without the others, the second is not (reason says why).
  enum class Result { kAccepted, kDuplicate, kDiscarded, kResend, kRefused };
  Result result = Result::kAccepted;
  bool stop = false;     // the chain should stop
  std::string reason;    // why it should stop
  bool yielded = false;  // stop only to let waiting chains run (not an error)
};

class JobStore;
struct StoredJob;

class Job {
 public:
  using Log = std::function<void(const std::string&)>;
  // `workFreed` is called (under the job's lock: it must not call back into the job) whenever
  // chains become free to lease: the bootstrap ended, leases expired, a chain yielded.
  // With a `store`, the job records its plan, every flush before it acknowledges it, its error
  // series and its end there (coordinator/job_store.h); its lease epochs start at `firstEpoch`.
  // A worker that fails one chain `maxChainFailures` times (its lease expires without the
  // chain's end, or it sends the chain a flush of the wrong size or with bad values) gets no
  // more of the job's chains; the job's progress names it and says why. A chain that has had
  // kWorkersToBlameAChain workers set aside fails the job: the chain, not the workers, is at
  // fault, and without this the job would wait for ever for a worker that can run it.
  static constexpr int kWorkersToBlameAChain = 3;
  Job(std::string id, JobSpec spec, SteadyClock::duration leaseDuration, std::string outputDir,
      Log log = {}, std::function<void()> workFreed = {}, JobStore* store = nullptr,
      uint64_t firstEpoch = 0, int maxChainFailures = 3);
  ~Job();  // cancels and joins the preparation thread
  Job(const Job&) = delete;
  Job& operator=(const Job&) = delete;

  // Starts loading and bootstrapping on a thread of the job's own.
  void start();
  // Instead of start(), for a job a durable coordinator remembers: a rendering job goes on from
  // its checkpoint and log at once (its scene loads on the job's thread meanwhile; the final
  // image waits for it), an ended one keeps its end, one that had not started rendering starts
  // again. `stored.spec` must be this job's spec.
  void restore(StoredJob stored);

  const std::string& id() const { return id_; }
  // As submitted: with --algorithm auto, settings.algorithm is not what renders (algorithm()).
  const JobSpec& spec() const { return spec_; }
  // The algorithm the chains run: the submitted one, or auto's pick once the plan has it.
  Algorithm algorithm() const;
  JobPhase phase() const;

  // Up to `max` chains for `worker`, if the job is rendering.
  std::vector<WorkerLease> lease(const std::string& worker, int max, SteadyClock::time_point now);
  bool renew(const std::string& worker, uint32_t chain, uint64_t epoch,
             SteadyClock::time_point now);
  // How a flush counts is in coordinator/flush_acceptance.cpp.
  // Validates and adds a flush. Not-OK statuses are the request's fault (unknown chain, wrong
  // size, out of order, bad values); a duplicate or a flush for a finished job is OK with the ack
  // saying so.
  // `wire`: the splats as they arrived, for the durable store to keep as they are.
  Status acceptFlush(const std::string& worker, uint64_t epoch, ChainFlush&& flush,
                     SteadyClock::time_point now, FlushAck* ack,
                     const EncodedSplats* wire = nullptr);
  // A worker's summed upload of several chains' flushes (coordinator/splat_aggregator.h's
  // FlushBatch), taken whole or not at all: when every entry is the next flush of its chain,
  // the film is added once and every entry counts; otherwise nothing counts and (*acks)[i] says
  // what entry i is: a duplicate (counted before: drop it), kResend (send it again without the
  // others) or kRefused (its reason). Not-OK statuses are the batch's fault as a whole (two
  // entries of one chain, an unsound film: every chain in it is charged a failure).
  Status acceptBatch(const std::string& worker, FlushBatch&& batch, SteadyClock::time_point now,
                     std::vector<FlushAck>* acks, const EncodedSplats* wire = nullptr);
  // Expires leases, enforces the time budget, finishes the job when every chain has ended.
  void tick(SteadyClock::time_point now);
  // Returns the phase after the cancellation (a job already over keeps its phase). Without
  // `record`, the store does not hear of it (a durable coordinator shutting down: the job goes
  // on after the restart).
  JobPhase cancel(bool record = true);

  JobProgress progress(uint32_t errorSeriesFrom = 0) const;
  // The final EXR on disk; FailedPrecondition (saying why) unless the job is done.
  Status imageFile(std::string* path) const;
  Status finalImage(Image* image, ImageMetadata* metadata) const;
  // The image as it stands: the final one once done, else the summed flushes resolved with
  // the work so far; kFailedPrecondition before any work arrived.
  Status currentImage(Image* image) const;
  // Leases held now, by worker.
  std::map<std::string, uint32_t> leaseHolders() const;
  // Blocks until the job is over or `timeout` passes; returns the phase.
  JobPhase waitForEnd(SteadyClock::duration timeout) const;
  // The renderer's job once loaded (null before): embedded workers run chains on it directly.
  std::shared_ptr<const RenderJob> renderJob() const;

 private:
  void prepare();
  void loadForRestore();
  void failLocked(const std::string& message);
  // Records the job's end in the store (when it has one); false, having failed the job, when it
  // cannot.
  void recordEndLocked();
  void checkpointLocked();
  void countFailureLocked(const std::string& worker, uint32_t chain, const std::string& why);
  // Whether the chain of a counted (or duplicate) flush goes on: `ack` gets stop and its reason
  // when the job's time is up, the worker no longer holds the lease, or the chain yields.
  // The one way a flush counts, a single one as a batch of one (acceptFlush): the film and each
  // entry checked, the batch made durable and added when every entry is its chain's next flush,
  // each entry answered. `filmName` names the film in a problem; (*outcomes)[i] and
  // (*problems)[i] are entry i's verdict (empty when the film or the job answered first).
  Status acceptLocked(const std::string& worker, FlushBatch&& batch, const std::string& filmName,
                      SteadyClock::time_point now, std::vector<FlushAck>* acks,
                      std::vector<FlushOutcome>* outcomes, std::vector<std::string>* problems,
                      const EncodedSplats* wire);
  void answerLocked(uint32_t chain, const std::string& worker, uint64_t epoch, bool accepted,
                    bool finished, int64_t mutations, FlushAck* ack);
  void enforceBudgetLocked(SteadyClock::time_point now);
  void finishIfCompleteLocked(SteadyClock::time_point now);
  void recordErrorLocked(SteadyClock::time_point now, bool force);
  Status notDoneStatusLocked() const;
  void log(const std::string& line) const {
    if (log_) log_("job " + id_ + ": " + line);
  }
  double secondsSince(SteadyClock::time_point t, SteadyClock::time_point now) const;

  const std::string id_;
  const JobSpec spec_;
  // spec_.settings as the plan left them (auto's algorithm, mlt's mix): what renders. Written
  // under mutex_ by prepare() and restore(), before the job leases any chain.
  RenderSettings settings_;
  const SteadyClock::duration leaseDuration_;
  const std::string outputDir_;
  SteadyClock::time_point submitted_;  // moved back by the time a restored job had run
  const Log log_;
  const std::function<void()> workFreed_;
  JobStore* const store_;
  const uint64_t firstEpoch_;
  const int maxChainFailures_;
  std::map<std::string, std::map<uint32_t, int>> chainFailures_;  // worker -> chain -> failures
  std::map<std::string, std::string> setAside_;                   // worker -> why
  std::map<uint32_t, std::set<std::string>> setAsideBy_;  // chain -> workers it had set aside

  mutable std::mutex mutex_;
  mutable std::condition_variable endedSignal_;
  std::thread preparer_;
  std::atomic<bool> cancelRequested_{false};

  JobPhase phase_ = JobPhase::kSubmitted;
  std::string error_;
  std::shared_ptr<RenderJob> renderJob_;
  BootstrapResult bootstrap_;
  std::optional<Image> reference_;
  std::unique_ptr<ChainScheduler> scheduler_;
  std::unique_ptr<SplatAggregator> aggregator_;
  int64_t plannedWork_ = 0;
  int width_ = 0, height_ = 0;
  double loadSeconds_ = 0;
  std::vector<std::string> warnings_;
  std::vector<std::string> renderPlan_;
  std::optional<SteadyClock::time_point> renderStarted_, endedAt_;
  std::vector<ErrorSample> errorSeries_;
  double metricsSeconds_ = 0;  // time spent computing error metrics, to keep it a small share
  uint64_t tailBytes_ = 0;     // flushes recorded since the store's last checkpoint
  std::optional<Image> finalImage_;
  ImageMetadata finalMetadata_;
  std::string imagePath_;
};

}  // namespace farm
