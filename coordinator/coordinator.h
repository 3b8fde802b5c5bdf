#pragma once
// The coordinator without the network: jobs, workers and their leases, the scene blob store.
// The gRPC services (grpc_service.h) and the embedded `farm render` both drive this class, so
// the pipeline is the same in one process and on a cluster.
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "coordinator/blob_store.h"
#include "coordinator/job.h"
#include "coordinator/status.h"

namespace farm {

struct CoordinatorOptions {
  std::string dataDir;  // blobs, laid-out bundles and final images; created if needed
  // Jobs, their plans and every accepted flush in dataDir/coordinator.db (job_store.h): a
  // coordinator started again on the same directory resumes every job. Without it, job records
  // live in memory only.
  bool durable = false;
  uint64_t checkpointBytes = 0;  // durable: see JobStore::setCheckpointBytes
  int maxChainFailures = 3;      // a worker failing one chain this often gets none of its job's
  double leaseSeconds = 30;      // a lease lives this long without a flush or renewal
  double tickSeconds = 0.1;      // how often leases and time budgets are checked
  // Jobs not yet done, failed or cancelled that the coordinator holds at once; a submit beyond
  // is kResourceExhausted (each holds films and a bootstrap in memory).
  int maxActiveJobs = 100;
  std::function<void(const std::string&)> log;  // one line per event worth an operator's eye
};

struct WorkerInfo {
  std::string version, host;
  int threads = 1;
  std::set<Algorithm> capabilities;
};

// A registered worker as the web page and /metrics show it.
struct WorkerStatus {
  std::string id, host, version;
  int threads = 0;
  double registeredSeconds = 0;   // since it registered
  double lastContactSeconds = 0;  // since its last call (lease, renewal, flush)
  uint32_t chains = 0;            // leases it holds now, over all jobs
  int64_t workAccepted = 0;       // mutations or samples of its accepted flushes
  int64_t flushesAccepted = 0;
};

struct LeaseRef {
  std::string jobId;
  uint32_t chain = 0;
  uint64_t epoch = 0;
};

class JobStore;

class Coordinator {
 public:
  // Throws std::runtime_error when a durable coordinator cannot open or read its database.
  explicit Coordinator(CoordinatorOptions options);
  ~Coordinator();  // cancels what still runs and joins every thread
  Coordinator(const Coordinator&) = delete;
  Coordinator& operator=(const Coordinator&) = delete;

  BlobStore& blobs() { return blobs_; }
  bool durable() const { return store_ != nullptr; }
  double leaseSeconds() const { return options_.leaseSeconds; }
  const std::string& dataDir() const { return options_.dataDir; }

  // --- Client side
  // Validates the settings and inputs and starts the job (loading and bootstrap run on a
  // thread of the job's own).
  Status submit(JobSpec spec, std::string* jobId);
  Status progress(const std::string& jobId, uint32_t errorSeriesFrom, JobProgress* out) const;
  Status cancel(const std::string& jobId, JobPhase* phase);
  std::vector<JobProgress> list() const;  // in submission order, without error series
  Status imageFile(const std::string& jobId, std::string* path) const;
  Status finalImage(const std::string& jobId, Image* image, ImageMetadata* metadata) const;
  Status waitForEnd(const std::string& jobId, SteadyClock::duration timeout, JobPhase* phase) const;
  std::shared_ptr<const RenderJob> renderJob(const std::string& jobId) const;
  // The image as it stands (rendering or done); kFailedPrecondition before any work arrived.
  Status currentImage(const std::string& jobId, Image* image) const;
  // Every registered worker, in id order.
  std::vector<WorkerStatus> workers() const;

  // --- Worker side
  Status registerWorker(const WorkerInfo& info, std::string* workerId);
  // Chains from the oldest rendering job first, only of algorithms the worker runs. When none
  // is free, waits up to `wait` (capped at kMaxLeaseWait) for one to become free (a job's
  // bootstrap ending, a lease expiring) and answers at once when it does; `abandoned`, checked
  // every second, ends the wait early (the caller went away).
  static constexpr SteadyClock::duration kMaxLeaseWait = std::chrono::seconds(10);
  Status leaseChains(const std::string& workerId, int max, std::vector<WorkerLease>* leases,
                     SteadyClock::duration wait = SteadyClock::duration::zero(),
                     const std::function<bool()>& abandoned = {});
  // Ends every lease wait now and refuses new ones (the server is shutting down).
  void releaseLeaseWaiters();
  // Makes every lease wait look for chains again and re-check its `abandoned` now; jobs call it
  // when chains become free, an embedded worker when it stops.
  void wakeLeaseWaiters();
  Status renewLeases(const std::string& workerId, const std::vector<LeaseRef>& leases,
                     std::vector<LeaseRef>* lost);
  // `wire`: the splats as they arrived (proto/splat_codec.h), kept so by a durable store.
  Status acceptFlush(const std::string& workerId, const std::string& jobId, uint64_t epoch,
                     ChainFlush&& flush, FlushAck* ack, const EncodedSplats* wire = nullptr);
  // Several chains' flushes of one job summed into one film (Job::acceptBatch).
  Status acceptBatch(const std::string& workerId, const std::string& jobId, FlushBatch&& batch,
                     std::vector<FlushAck>* acks, const EncodedSplats* wire = nullptr);

  // Expires leases, enforces time budgets, finishes jobs; also runs on a timer. Tests pass a
  // later `now` to make leases expire without waiting for them.
  void tick(SteadyClock::time_point now = SteadyClock::now());

 private:
  std::shared_ptr<Job> findJob(const std::string& jobId) const;
  Status findWorker(const std::string& workerId, WorkerInfo* info) const;
  void housekeeping();
  std::vector<WorkerLease> leaseNow(const std::string& workerId, const WorkerInfo& worker, int max);

  void restoreJobs();
  SteadyClock::duration leaseDuration() const;

  const CoordinatorOptions options_;
  BlobStore blobs_;
  std::unique_ptr<JobStore> store_;  // durable coordinators only; outlives the jobs

  // Lease waits sleep on workWake_ until workGeneration_ moves (wakeLeaseWaiters) or they time out;
  // at most kMaxLeaseWaiters at once, since each holds one of the server's threads.
  // Declared before the jobs, which signal them, so that they outlive the jobs.
  static constexpr int kMaxLeaseWaiters = 256;
  std::mutex workMutex_;
  std::condition_variable workWake_;
  uint64_t workGeneration_ = 0;
  int leaseWaiters_ = 0;
  bool leaseWaitsReleased_ = false;

  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<Job>> jobs_;  // submission order
  std::map<std::string, std::shared_ptr<Job>> jobsById_;
  std::map<std::string, WorkerInfo> workers_;
  struct WorkerActivity {
    SteadyClock::time_point registered, lastContact;
    int64_t workAccepted = 0, flushesAccepted = 0;
  };
  // Touched by every worker call (findWorker is const: its bookkeeping is mutable).
  mutable std::map<std::string, WorkerActivity> activity_;
  void countAccepted(const std::string& workerId, int64_t work, int64_t flushes);

  std::mutex housekeepingMutex_;
  std::condition_variable housekeepingWake_;
  bool shuttingDown_ = false;
  std::thread housekeeper_;
};

// A random identifier: prefix + 12 hex digits.
std::string randomId(const std::string& prefix);

}  // namespace farm
