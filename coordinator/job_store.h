#pragma once
// The durable coordinator's memory (farm-coordinator --data DIR): jobs, their plans, the index
// of every accepted flush and the error series in one SQLite database (WAL mode, synchronous
// FULL; its tables in store_schema.h, its records in store_records.h), the flushes' bytes and
// the checkpoints' films in files beside it (DIR/logs, flush_log.h), so that a coordinator
// killed at any moment and started again on the same directory resumes every job where its last
// acknowledged flush left it.
//
// A flush is written (appended to the log and synced, then its row committed) before it is
// summed and acknowledged: a crash before the commit loses a flush the worker was never told
// was accepted (it sends it again; the log's bytes past the last row are cut off); a crash after
// it keeps the flush, and the worker's retry is a duplicate. The log of a job's flushes is
// folded now and then into a checkpoint (the summed film and every chain's resume point) in the
// same transaction that deletes the folded rows, so a restart reads one checkpoint and replays a
// bounded tail of the log, never summing a flush twice.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/render/render_job.h"
#include "coordinator/chain_scheduler.h"
#include "coordinator/flush_log.h"
#include "coordinator/job.h"
#include "coordinator/splat_aggregator.h"
#include "coordinator/status.h"
#include "coordinator/store_records.h"
#include "proto/bundle_manifest.h"
#include "proto/splat_codec.h"

struct sqlite3;

namespace farm {

// A job as the store remembers it.
struct StoredJob {
  std::string id;
  JobSpec spec;
  // kSubmitted (not yet rendering: prepare it again), kRendering, or a terminal phase.
  JobPhase phase = JobPhase::kSubmitted;
  std::string error;
  double elapsedSeconds = 0;  // of the job's clock when last written
  std::optional<JobPlan> plan;
  // From the newest checkpoint (absent: none yet), then the flushes accepted after it, in order.
  std::optional<SplatAggregator::Snapshot> checkpoint;
  std::vector<ChainScheduler::ChainSnapshot> checkpointChains;
  std::vector<FlushBatch> tail;  // a single flush as a batch of one
  std::vector<ErrorSample> errorSeries;
};

class JobStore {
 public:
  // Opens (or creates) DIR/coordinator.db and DIR/logs. Each open is a new generation (see
  // generation()).
  static Status open(const std::string& dir, std::unique_ptr<JobStore>* store);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // 1 for a new database, one more at every open: lease epochs of this run start at
  // generation << 32, above every epoch an earlier run handed out.
  uint64_t generation() const { return generation_; }
  const std::string& path() const { return path_; }

  // A job's log is folded into a checkpoint once it holds this many bytes; 0 (the default):
  // eight times the job's sums (the film in double, at least 1 MiB each). A checkpoint rewrites
  // the whole film, so folding rarely keeps it a small share of the ingest (at 256x256, folding
  // every film's worth cost 29 ms a dense flush against 8 ms without folding), while a restart
  // replays at most eight films' worth of flushes. Tests set 1 to checkpoint after every flush.
  void setCheckpointBytes(uint64_t bytes) { checkpointBytes_ = bytes; }
  uint64_t checkpointThreshold(uint64_t filmBytes) const {
    return checkpointBytes_ > 0 ? checkpointBytes_ : 8 * std::max<uint64_t>(filmBytes, 1 << 20);
  }

  Status addBundle(const std::string& hash, const BundleManifest& manifest);
  Status loadBundles(std::vector<std::pair<std::string, BundleManifest>>* bundles);

  Status addJob(const std::string& id, const JobSpec& spec);
  // Any phase. A terminal phase also drops the job's flush log and its sums (a done job's image
  // is on disk), keeping only `finalCounts`' counts (work done, rays, tallies) when given.
  Status setPhase(const std::string& id, JobPhase phase, const std::string& error,
                  double elapsedSeconds, const SplatAggregator::Snapshot* finalCounts = nullptr);
  // The job renders from now on with this plan.
  Status savePlan(const std::string& id, const JobPlan& plan, double elapsedSeconds);
  // Records an accepted batch (one record: its film once, then its entries; a single flush is a
  // batch of one); *tailBytes is then the size of the job's log since its last checkpoint (the
  // caller checkpoints when it grows past what a restart should replay). `wire`: the film's
  // splats as they arrived (they decode to batch.film.splats), kept as they are instead of
  // encoded again; null: encoded from the film.
  Status appendBatch(const std::string& id, const FlushBatch& batch, double elapsedSeconds,
                     uint64_t* tailBytes, const EncodedSplats* wire = nullptr);
  // Replaces the job's log so far by this state of its sums (a file beside the log) and chains.
  // Reads the aggregator's films in place: the caller holds what guards them (the job's lock).
  Status checkpoint(const std::string& id, const SplatAggregator& sums,
                    const std::vector<ChainScheduler::ChainSnapshot>& chains);
  Status addErrorSample(const std::string& id, uint32_t index, const ErrorSample& sample);

  // Every job, in submission order.
  Status loadJobs(std::vector<StoredJob>* jobs);

 private:
  JobStore(sqlite3* db, std::string path, std::string logDir);
  Status appendRecord(const std::string& id, const std::string& record, const std::string& what,
                      double elapsedSeconds, uint64_t* tailBytes);
  // Opens the job's log cut at the end of its last committed record.
  Status openLogLocked(const std::string& id);
  Status exec(const char* sql);
  // BEGIN IMMEDIATE, `body`, COMMIT; ROLLBACK (and `what` with SQLite's reason) when the body
  // returns false or the commit fails.
  Status transaction(const std::string& what, const std::function<bool()>& body);
  Status fail(const std::string& what) const;

  sqlite3* db_;
  const std::string path_;
  FlushLog log_;  // DIR/logs
  uint64_t generation_ = 0;
  uint64_t checkpointBytes_ = 0;
  std::mutex mutex_;  // one connection, one writer at a time
};

}  // namespace farm
