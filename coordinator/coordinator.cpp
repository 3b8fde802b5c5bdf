#include "coordinator/coordinator.h"

#include <algorithm>
#include <filesystem>
#include <random>

#include "coordinator/job_store.h"

namespace farm {
namespace fs = std::filesystem;

std::string randomId(const std::string& prefix) {
  static std::mutex mutex;
  static std::mt19937_64 rng{std::random_device{}()};
  std::lock_guard<std::mutex> lock(mutex);
  static const char* kHex = "0123456789abcdef";
  uint64_t bits = rng();
  std::string id = prefix;
  for (int i = 0; i < 12; ++i, bits >>= 4) id.push_back(kHex[bits & 0xf]);
  return id;
}

Coordinator::Coordinator(CoordinatorOptions options)
    : options_(std::move(options)), blobs_(options_.dataDir) {
  if (options_.durable) {
    Status st = JobStore::open(options_.dataDir, &store_);
    if (!st.isOk()) throw std::runtime_error(st.message());
    store_->setCheckpointBytes(options_.checkpointBytes);
    restoreJobs();
  }
  housekeeper_ = std::thread([this] { housekeeping(); });
}

SteadyClock::duration Coordinator::leaseDuration() const {
  return std::chrono::duration_cast<SteadyClock::duration>(
      std::chrono::duration<double>(options_.leaseSeconds));
}

void Coordinator::restoreJobs() {
  std::vector<std::pair<std::string, BundleManifest>> bundles;
  Status st = store_->loadBundles(&bundles);
  if (!st.isOk()) throw std::runtime_error(st.message());
  for (const auto& [hash, manifest] : bundles) {
    if (blobs_.registerBundle(manifest) != hash) {
      throw std::runtime_error("coordinator database " + store_->path() + ": bundle " + hash +
                               " does not hash to its name");
    }
  }
  std::vector<StoredJob> stored;
  st = store_->loadJobs(&stored);
  if (!st.isOk()) throw std::runtime_error(st.message());
  const uint64_t firstEpoch = store_->generation() << 32;
  for (StoredJob& record : stored) {
    const std::string id = record.id;
    const std::string outputDir = (fs::path(options_.dataDir) / "jobs" / id).string();
    auto job = std::make_shared<Job>(
        id, record.spec, leaseDuration(), outputDir, options_.log, [this] { wakeLeaseWaiters(); },
        store_.get(), firstEpoch, options_.maxChainFailures);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      jobs_.push_back(job);
      jobsById_[id] = job;
    }
    job->restore(std::move(record));
  }
  if (options_.log) {
    options_.log("coordinator database " + store_->path() + " (run " +
                 std::to_string(store_->generation()) + "): " + std::to_string(stored.size()) +
                 " job(s) remembered");
  }
}

Coordinator::~Coordinator() {
  {
    std::lock_guard<std::mutex> lock(housekeepingMutex_);
    shuttingDown_ = true;
  }
  housekeepingWake_.notify_all();
  housekeeper_.join();
  releaseLeaseWaiters();
  std::vector<std::shared_ptr<Job>> jobs;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs = jobs_;
  }
  // A durable coordinator's jobs are not over: a restart resumes them. Their threads stop all
  // the same, and nothing of it reaches the database.
  for (auto& job : jobs) job->cancel(/*record=*/!store_);
}

void Coordinator::housekeeping() {
  std::unique_lock<std::mutex> lock(housekeepingMutex_);
  const auto period = std::chrono::duration<double>(options_.tickSeconds);
  while (!shuttingDown_) {
    housekeepingWake_.wait_for(lock, period, [this] { return shuttingDown_; });
    if (shuttingDown_) break;
    lock.unlock();
    tick();
    lock.lock();
  }
}

void Coordinator::tick(SteadyClock::time_point now) {
  std::vector<std::shared_ptr<Job>> jobs;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs = jobs_;
  }
  for (auto& job : jobs) job->tick(now);
}

std::shared_ptr<Job> Coordinator::findJob(const std::string& jobId) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = jobsById_.find(jobId);
  return it == jobsById_.end() ? nullptr : it->second;
}

namespace {
Status unknownJob(const std::string& jobId) {
  std::string shown = jobId.size() > 80 ? jobId.substr(0, 80) + "..." : jobId;
  return Status::notFound("unknown job id '" + shown + "'");
}
}  // namespace

Status Coordinator::submit(JobSpec spec, std::string* jobId) {
  // Every setting is checked in one place, RenderSettings::validate().
  std::string problem = spec.settings.validate();
  if (!problem.empty()) return Status::invalidArgument("invalid render settings: " + problem);
  std::error_code ec;
  if (!fs::is_regular_file(spec.scenePath, ec)) {
    return Status::invalidArgument("scene file '" + spec.scenePath + "' does not exist");
  }
  if (!spec.referencePath.empty() && !fs::is_regular_file(spec.referencePath, ec)) {
    return Status::invalidArgument("reference image '" + spec.referencePath + "' does not exist");
  }
  // Counted from a snapshot, outside the lock (a job's phase takes the job's own lock); two
  // submits at once may pass the limit by one each.
  std::vector<std::shared_ptr<Job>> held;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    held = jobs_;
  }
  const auto active = std::count_if(held.begin(), held.end(), [](const std::shared_ptr<Job>& j) {
    return !isTerminal(j->phase());
  });
  if (active >= options_.maxActiveJobs) {
    return {StatusCode::kResourceExhausted,
            std::to_string(active) + " jobs are already queued or rendering here, the most this " +
                "coordinator holds (--max-jobs " + std::to_string(options_.maxActiveJobs) +
                "): wait for one to finish or cancel one"};
  }
  std::shared_ptr<Job> job;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string id;
    do {
      id = randomId("job-");
    } while (jobsById_.count(id));
    const std::string outputDir = (fs::path(options_.dataDir) / "jobs" / id).string();
    if (store_) {
      // Durable before the client hears of the job: its bundle first, then the job itself.
      BundleManifest manifest;
      if (!spec.bundleHash.empty() && blobs_.findBundle(spec.bundleHash, &manifest)) {
        Status st = store_->addBundle(spec.bundleHash, manifest);
        if (!st.isOk()) return st;
      }
      Status st = store_->addJob(id, spec);
      if (!st.isOk()) return st;
    }
    job = std::make_shared<Job>(
        id, std::move(spec), leaseDuration(), outputDir, options_.log,
        [this] { wakeLeaseWaiters(); }, store_.get(), store_ ? store_->generation() << 32 : 0,
        options_.maxChainFailures);
    if (options_.log) {
      options_.log("job " + id + ": submitted (" + job->spec().name + ", " +
                   algorithmName(job->spec().settings.algorithm) + ")");
    }
    jobs_.push_back(job);
    jobsById_[id] = job;
    *jobId = id;
  }
  job->start();
  return Status::ok();
}

Status Coordinator::progress(const std::string& jobId, uint32_t errorSeriesFrom,
                             JobProgress* out) const {
  auto job = findJob(jobId);
  if (!job) return unknownJob(jobId);
  *out = job->progress(errorSeriesFrom);
  return Status::ok();
}

Status Coordinator::cancel(const std::string& jobId, JobPhase* phase) {
  auto job = findJob(jobId);
  if (!job) return unknownJob(jobId);
  JobPhase after = job->cancel();
  if (phase) *phase = after;
  return Status::ok();
}

std::vector<JobProgress> Coordinator::list() const {
  std::vector<std::shared_ptr<Job>> jobs;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs = jobs_;
  }
  std::vector<JobProgress> out;
  for (auto& job : jobs) out.push_back(job->progress(UINT32_MAX));
  return out;
}

Status Coordinator::imageFile(const std::string& jobId, std::string* path) const {
  auto job = findJob(jobId);
  if (!job) return unknownJob(jobId);
  return job->imageFile(path);
}

Status Coordinator::finalImage(const std::string& jobId, Image* image,
                               ImageMetadata* metadata) const {
  auto job = findJob(jobId);
  if (!job) return unknownJob(jobId);
  return job->finalImage(image, metadata);
}

Status Coordinator::waitForEnd(const std::string& jobId, SteadyClock::duration timeout,
                               JobPhase* phase) const {
  auto job = findJob(jobId);
  if (!job) return unknownJob(jobId);
  JobPhase p = job->waitForEnd(timeout);
  if (phase) *phase = p;
  return Status::ok();
}

std::shared_ptr<const RenderJob> Coordinator::renderJob(const std::string& jobId) const {
  auto job = findJob(jobId);
  return job ? job->renderJob() : nullptr;
}

Status Coordinator::registerWorker(const WorkerInfo& info, std::string* workerId) {
  if (info.threads < 1 || info.threads > 4096) {
    return Status::invalidArgument("worker threads must be in [1, 4096], got " +
                                   std::to_string(info.threads));
  }
  if (info.capabilities.empty()) {
    return Status::invalidArgument("worker runs no algorithm this coordinator knows");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  std::string id;
  do {
    id = randomId("worker-");
  } while (workers_.count(id));
  workers_[id] = info;
  activity_[id].registered = activity_[id].lastContact = SteadyClock::now();
  *workerId = id;
  if (options_.log) {
    options_.log("worker " + id + " registered (" + info.host + ", " +
                 std::to_string(info.threads) + " threads, " + info.version + ")");
  }
  return Status::ok();
}

Status Coordinator::findWorker(const std::string& workerId, WorkerInfo* info) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = workers_.find(workerId);
  if (it == workers_.end()) {
    std::string shown = workerId.size() > 80 ? workerId.substr(0, 80) + "..." : workerId;
    return Status::notFound("unknown worker id '" + shown +
                            "' (register first; a restarted coordinator forgets workers)");
  }
  if (info) *info = it->second;
  activity_[workerId].lastContact = SteadyClock::now();
  return Status::ok();
}

void Coordinator::countAccepted(const std::string& workerId, int64_t work, int64_t flushes) {
  if (flushes == 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  WorkerActivity& a = activity_[workerId];
  a.workAccepted += work;
  a.flushesAccepted += flushes;
}

std::vector<WorkerStatus> Coordinator::workers() const {
  std::vector<std::shared_ptr<Job>> jobs;
  std::vector<WorkerStatus> out;
  const auto now = SteadyClock::now();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs = jobs_;
    for (const auto& [id, info] : workers_) {
      WorkerStatus w;
      w.id = id;
      w.host = info.host;
      w.version = info.version;
      w.threads = info.threads;
      auto a = activity_.find(id);
      if (a != activity_.end()) {
        w.registeredSeconds = std::chrono::duration<double>(now - a->second.registered).count();
        w.lastContactSeconds = std::chrono::duration<double>(now - a->second.lastContact).count();
        w.workAccepted = a->second.workAccepted;
        w.flushesAccepted = a->second.flushesAccepted;
      }
      out.push_back(std::move(w));
    }
  }
  for (const auto& job : jobs) {
    for (const auto& [holder, chains] : job->leaseHolders()) {
      for (WorkerStatus& w : out) {
        if (w.id == holder) w.chains += chains;
      }
    }
  }
  return out;
}

Status Coordinator::currentImage(const std::string& jobId, Image* image) const {
  auto job = findJob(jobId);
  if (!job) return unknownJob(jobId);
  return job->currentImage(image);
}

std::vector<WorkerLease> Coordinator::leaseNow(const std::string& workerId,
                                               const WorkerInfo& worker, int max) {
  std::vector<std::shared_ptr<Job>> jobs;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs = jobs_;
  }
  const auto now = SteadyClock::now();
  std::vector<WorkerLease> leases;
  for (auto& job : jobs) {
    if (int(leases.size()) >= max) break;
    if (!worker.capabilities.count(job->algorithm())) continue;
    for (WorkerLease& lease : job->lease(workerId, max - int(leases.size()), now)) {
      leases.push_back(std::move(lease));
    }
  }
  return leases;
}

Status Coordinator::leaseChains(const std::string& workerId, int max,
                                std::vector<WorkerLease>* leases, SteadyClock::duration wait,
                                const std::function<bool()>& abandoned) {
  WorkerInfo worker;
  Status status = findWorker(workerId, &worker);
  if (!status.isOk()) return status;
  if (max < 1 || max > 4096) {
    return Status::invalidArgument("max chains must be in [1, 4096], got " + std::to_string(max));
  }
  const auto deadline =
      SteadyClock::now() + std::clamp(wait, SteadyClock::duration::zero(), kMaxLeaseWait);
  bool waiting = false;
  for (;;) {
    // The generation is read before looking for chains, so that a chain freed between the
    // look and the wait still wakes the wait.
    uint64_t generation;
    {
      std::lock_guard<std::mutex> lock(workMutex_);
      generation = workGeneration_;
    }
    *leases = leaseNow(workerId, worker, max);
    if (!leases->empty()) break;
    std::unique_lock<std::mutex> lock(workMutex_);
    const auto now = SteadyClock::now();
    if (leaseWaitsReleased_ || now >= deadline || (abandoned && abandoned())) break;
    if (!waiting) {
      if (leaseWaiters_ >= kMaxLeaseWaiters) break;  // the worker retries on its own timer
      ++leaseWaiters_;
      waiting = true;
    }
    workWake_.wait_until(lock, std::min(deadline, now + std::chrono::seconds(1)),
                         [&] { return workGeneration_ != generation || leaseWaitsReleased_; });
  }
  if (waiting) {
    std::lock_guard<std::mutex> lock(workMutex_);
    --leaseWaiters_;
  }
  return Status::ok();
}

void Coordinator::wakeLeaseWaiters() {
  {
    std::lock_guard<std::mutex> lock(workMutex_);
    ++workGeneration_;
  }
  workWake_.notify_all();
}

void Coordinator::releaseLeaseWaiters() {
  {
    std::lock_guard<std::mutex> lock(workMutex_);
    leaseWaitsReleased_ = true;
  }
  workWake_.notify_all();
}

Status Coordinator::renewLeases(const std::string& workerId, const std::vector<LeaseRef>& leases,
                                std::vector<LeaseRef>* lost) {
  Status status = findWorker(workerId, nullptr);
  if (!status.isOk()) return status;
  const auto now = SteadyClock::now();
  lost->clear();
  for (const LeaseRef& ref : leases) {
    auto job = findJob(ref.jobId);
    if (!job || !job->renew(workerId, ref.chain, ref.epoch, now)) lost->push_back(ref);
  }
  return Status::ok();
}

Status Coordinator::acceptFlush(const std::string& workerId, const std::string& jobId,
                                uint64_t epoch, ChainFlush&& flush, FlushAck* ack,
                                const EncodedSplats* wire) {
  Status status = findWorker(workerId, nullptr);
  if (!status.isOk()) return status;
  auto job = findJob(jobId);
  if (!job) return unknownJob(jobId);
  const int64_t work = flush.mutations;
  status = job->acceptFlush(workerId, epoch, std::move(flush), SteadyClock::now(), ack, wire);
  if (status.isOk() && ack->result == FlushAck::Result::kAccepted) countAccepted(workerId, work, 1);
  return status;
}

Status Coordinator::acceptBatch(const std::string& workerId, const std::string& jobId,
                                FlushBatch&& batch, std::vector<FlushAck>* acks,
                                const EncodedSplats* wire) {
  Status status = findWorker(workerId, nullptr);
  if (!status.isOk()) return status;
  auto job = findJob(jobId);
  if (!job) return unknownJob(jobId);
  std::vector<int64_t> work;
  for (const auto& entry : batch.entries) work.push_back(entry.mutations);
  status = job->acceptBatch(workerId, std::move(batch), SteadyClock::now(), acks, wire);
  if (status.isOk()) {
    int64_t accepted = 0, flushes = 0;
    for (size_t i = 0; i < acks->size() && i < work.size(); ++i) {
      if ((*acks)[i].result != FlushAck::Result::kAccepted) continue;
      accepted += work[i];
      ++flushes;
    }
    countAccepted(workerId, accepted, flushes);
  }
  return status;
}

}  // namespace farm
