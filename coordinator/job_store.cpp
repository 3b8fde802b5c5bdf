#include "coordinator/job_store.h"

#include <sqlite3.h>

#include <filesystem>
#include <functional>

#include "coordinator/store_schema.h"
#include "proto/splat_codec.h"

namespace farm {
namespace fs = std::filesystem;
using store::Statement;

JobStore::JobStore(sqlite3* db, std::string path, std::string logDir)
    : db_(db), path_(std::move(path)), log_(std::move(logDir)) {}

JobStore::~JobStore() {
  sqlite3_close(db_);
}

Status JobStore::openLogLocked(const std::string& id) {
  if (log_.isOpen(id)) return Status::ok();
  Statement q(db_, "SELECT IFNULL(MAX(offset + length), 0) FROM flushes WHERE job = ?");
  q.bind(1, id);
  if (q.step() != SQLITE_ROW) return fail("cannot read the log of job " + id);
  return log_.open(id, uint64_t(q.integer(0)));
}

Status JobStore::fail(const std::string& what) const {
  return Status(StatusCode::kInternal,
                "coordinator database " + path_ + ": " + what + ": " + sqlite3_errmsg(db_));
}

Status JobStore::transaction(const std::string& what, const std::function<bool()>& body) {
  if (Status st = exec("BEGIN IMMEDIATE"); !st.isOk()) return st;
  // The body's statements are finalized when it returns: a statement still stepping would
  // keep COMMIT from ending the transaction.
  if (!body()) {
    Status st = fail(what);
    exec("ROLLBACK");
    return st;
  }
  if (sqlite3_exec(db_, "COMMIT", nullptr, nullptr, nullptr) != SQLITE_OK) {
    Status st = fail(what);
    exec("ROLLBACK");
    return st;
  }
  return Status::ok();
}

Status JobStore::exec(const char* sql) {
  char* message = nullptr;
  if (sqlite3_exec(db_, sql, nullptr, nullptr, &message) != SQLITE_OK) {
    std::string m = message ? message : "unknown error";
    sqlite3_free(message);
    return Status(StatusCode::kInternal, "coordinator database " + path_ + ": " + m);
  }
  return Status::ok();
}

Status JobStore::open(const std::string& dir, std::unique_ptr<JobStore>* store) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  const std::string path = (fs::path(dir) / "coordinator.db").string();
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
      SQLITE_OK) {
    std::string m = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    return Status::internal("cannot open the coordinator database " + path + ": " + m);
  }
  const std::string logDir = (fs::path(dir) / "logs").string();
  fs::create_directories(logDir, ec);
  if (ec) {
    sqlite3_close(db);
    return Status::internal("cannot create " + logDir + ": " + ec.message());
  }
  std::unique_ptr<JobStore> s(new JobStore(db, path, logDir));
  sqlite3_busy_timeout(db, 5000);
  // WAL: readers never block the writer, and a commit is one append. synchronous=FULL: a
  // commit is on disk when it returns, so an acknowledged flush survives a power cut too.
  for (const char* pragma :
       {"PRAGMA page_size=65536", "PRAGMA journal_mode=WAL", "PRAGMA synchronous=FULL"}) {
    if (Status st = s->exec(pragma); !st.isOk()) return st;
  }
  if (std::string why; !store::createTables(db, &why)) {
    return Status::internal("coordinator database " + path + ": " + why);
  }
  int64_t schema = store::kSchemaVersion;
  Status st = s->transaction("cannot initialize", [&] {
    Statement bump(db,
                   "INSERT INTO meta(key, value) VALUES('generation', 1) "
                   "ON CONFLICT(key) DO UPDATE SET value = value + 1 RETURNING value");
    if (!store::migrate(db, &schema) || bump.step() != SQLITE_ROW) return false;
    s->generation_ = uint64_t(bump.integer(0));
    return bump.step() == SQLITE_DONE;
  });
  if (schema != store::kSchemaVersion) {
    return Status::failedPrecondition("coordinator database " + path + " has schema version " +
                                      std::to_string(schema) + "; this coordinator reads " +
                                      std::to_string(store::kSchemaVersion));
  }
  if (!st.isOk()) return st;
  *store = std::move(s);
  return Status::ok();
}

Status JobStore::addBundle(const std::string& hash, const BundleManifest& manifest) {
  const std::string record = store::encodeBundle(manifest);
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, "INSERT OR IGNORE INTO bundles(hash, manifest) VALUES(?, ?)");
  if (!q.bind(1, hash).blob(2, record).run()) return fail("cannot add a bundle");
  return Status::ok();
}

Status JobStore::loadBundles(std::vector<std::pair<std::string, BundleManifest>>* bundles) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, "SELECT hash, manifest FROM bundles");
  int rc;
  while ((rc = q.step()) == SQLITE_ROW) {
    BundleManifest manifest;
    if (!store::decodeBundle(q.bytes(1), &manifest)) {
      return Status::internal("coordinator database " + path_ + ": unreadable bundle " +
                              q.bytes(0));
    }
    bundles->emplace_back(q.bytes(0), std::move(manifest));
  }
  if (rc != SQLITE_DONE) return fail("cannot read bundles");
  return Status::ok();
}

Status JobStore::addJob(const std::string& id, const JobSpec& spec) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, "INSERT INTO jobs(id, spec, phase) VALUES(?, ?, ?)");
  if (!q.bind(1, id)
           .blob(2, store::encodeSpec(spec))
           .bind(3, int64_t(store::phaseCode(JobPhase::kSubmitted)))
           .run()) {
    return fail("cannot add job " + id);
  }
  return Status::ok();
}

Status JobStore::setPhase(const std::string& id, JobPhase phase, const std::string& error,
                          double elapsedSeconds, const SplatAggregator::Snapshot* finalCounts) {
  std::string counts;
  if (finalCounts) {
    if (!finalCounts->sums.empty() || !finalCounts->groupSums.empty()) {
      throw std::invalid_argument("JobStore::setPhase keeps an ended job's counts, not its film");
    }
    counts = store::encodeCheckpoint(*finalCounts, {});
  }
  std::lock_guard<std::mutex> lock(mutex_);
  Status st = transaction("cannot record job " + id + " as " + jobPhaseName(phase), [&] {
    if (!Statement(db_, "UPDATE jobs SET phase = ?, error = ?, elapsed = ? WHERE id = ?")
             .bind(1, int64_t(store::phaseCode(phase)))
             .bind(2, error)
             .bind(3, elapsedSeconds)
             .bind(4, id)
             .run()) {
      return false;
    }
    if (!isTerminal(phase)) return true;
    // Over: the log and the sums are folded into the image (or thrown away); what stays is the
    // counts `farm status` shows.
    const bool counted =
        finalCounts ? Statement(db_, "INSERT OR REPLACE INTO checkpoints(job, record) VALUES(?, ?)")
                          .bind(1, id)
                          .blob(2, counts)
                          .run()
                    : Statement(db_, "DELETE FROM checkpoints WHERE job = ?").bind(1, id).run();
    return counted &&
           Statement(db_, "UPDATE jobs SET tail_bytes = 0 WHERE id = ?").bind(1, id).run() &&
           Statement(db_, "DELETE FROM flushes WHERE job = ?").bind(1, id).run();
  });
  if (st.isOk() && isTerminal(phase)) log_.removeJob(id);
  return st;
}

Status JobStore::savePlan(const std::string& id, const JobPlan& plan, double elapsedSeconds) {
  const std::string record = store::encodePlan(plan);
  std::lock_guard<std::mutex> lock(mutex_);
  return transaction("cannot record the plan of job " + id, [&] {
    return Statement(db_, "INSERT OR REPLACE INTO plans(job, record) VALUES(?, ?)")
               .bind(1, id)
               .blob(2, record)
               .run() &&
           Statement(db_, "UPDATE jobs SET phase = ?, elapsed = ? WHERE id = ?")
               .bind(1, int64_t(store::phaseCode(JobPhase::kRendering)))
               .bind(2, elapsedSeconds)
               .bind(3, id)
               .run();
  });
}

Status JobStore::appendBatch(const std::string& id, const FlushBatch& batch, double elapsedSeconds,
                             uint64_t* tailBytes, const EncodedSplats* wire) {
  return appendRecord(
      id, store::encodeBatch(batch, wire),
      "cannot record a batch of " + std::to_string(batch.entries.size()) + " flushes of job " + id,
      elapsedSeconds, tailBytes);
}

Status JobStore::appendRecord(const std::string& id, const std::string& record,
                              const std::string& what, double elapsedSeconds, uint64_t* tailBytes) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (Status st = openLogLocked(id); !st.isOk()) return st;
  // The record goes beside the database, on disk before the row that points at it is
  // committed (flush_log.h).
  uint64_t offset = 0;
  if (Status st = log_.write(id, record, &offset); !st.isOk()) {
    return Status::internal(what + ": " + st.message());
  }
  int64_t tail = 0;
  Status st = transaction(what, [&] {
    if (!Statement(db_,
                   "INSERT INTO flushes(job, seq, offset, length) VALUES(?1, "
                   "(SELECT IFNULL(MAX(seq), 0) + 1 FROM flushes WHERE job = ?1), ?2, ?3)")
             .bind(1, id)
             .bind(2, int64_t(offset))
             .bind(3, int64_t(record.size()))
             .run()) {
      return false;
    }
    Statement update(db_,
                     "UPDATE jobs SET elapsed = ?, tail_bytes = tail_bytes + ? WHERE id = ? "
                     "RETURNING tail_bytes");
    update.bind(1, elapsedSeconds).bind(2, int64_t(record.size())).bind(3, id);
    if (update.step() != SQLITE_ROW) return false;
    tail = update.integer(0);
    return update.step() == SQLITE_DONE;
  });
  if (!st.isOk()) return st;  // the bytes stay unreferenced; the next append overwrites them
  log_.commit(id, record.size());
  if (tailBytes) *tailBytes = uint64_t(tail);
  return st;
}

Status JobStore::checkpoint(const std::string& id, const SplatAggregator& sums,
                            const std::vector<ChainScheduler::ChainSnapshot>& chains) {
  // Compressed from the aggregator's films as they are (outside the store's lock): a copy of
  // them would double the coordinator's memory for the moment (570 MiB at 4K, four groups).
  const std::string frame = store::encodeFilms(sums);
  std::lock_guard<std::mutex> lock(mutex_);
  // The film is on disk under its own name before the record that names it commits, and the
  // previous film is removed only after (flush_log.h).
  std::string name;
  if (Status st = log_.writeFilm(id, generation_, frame, &name); !st.isOk()) return st;
  const std::string record = store::encodeCheckpoint(sums.snapshot(false), chains, name);
  Status st = transaction("cannot checkpoint job " + id, [&] {
    return Statement(db_, "INSERT OR REPLACE INTO checkpoints(job, record) VALUES(?, ?)")
               .bind(1, id)
               .blob(2, record)
               .run() &&
           Statement(db_, "UPDATE jobs SET tail_bytes = 0 WHERE id = ?").bind(1, id).run() &&
           Statement(db_, "DELETE FROM flushes WHERE job = ?").bind(1, id).run();
  });
  if (!st.isOk()) {
    log_.discardFilm(name);
    return st;
  }
  log_.reset(id);
  log_.adoptFilm(id, name);
  return st;
}

Status JobStore::addErrorSample(const std::string& id, uint32_t index, const ErrorSample& e) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_,
              "INSERT OR REPLACE INTO errors(job, idx, elapsed, samples, rmse, relmse, "
              "estimated) VALUES(?, ?, ?, ?, ?, ?, ?)");
  if (!q.bind(1, id)
           .bind(2, int64_t(index))
           .bind(3, e.elapsedSeconds)
           .bind(4, e.samples)
           .bind(5, e.rmse)
           .bind(6, e.relMse)
           .bind(7, e.estimatedRelMse)
           .run()) {
    return fail("cannot record an error sample of job " + id);
  }
  return Status::ok();
}

Status JobStore::loadJobs(std::vector<StoredJob>* jobs) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_,
              "SELECT id, spec, phase, error, elapsed, "
              "(SELECT record FROM plans WHERE job = jobs.id), "
              "(SELECT record FROM checkpoints WHERE job = jobs.id) FROM jobs ORDER BY ord");
  int rc;
  while ((rc = q.step()) == SQLITE_ROW) {
    StoredJob job;
    job.id = q.bytes(0);
    std::string problem;
    auto corrupt = [&](const std::string& what) {
      return Status(StatusCode::kDataLoss,
                    "coordinator database " + path_ + ": job " + job.id + ": " + what);
    };
    if (!store::decodeSpec(q.bytes(1), &job.spec, &problem)) return corrupt(problem);
    if (!store::phaseFromCode(q.integer(2), &job.phase)) return corrupt("unknown phase");
    job.error = q.bytes(3);
    job.elapsedSeconds = q.real(4);
    if (!q.isNull(5)) {
      JobPlan plan;
      if (!store::decodePlan(q.bytes(5), &plan, &problem)) return corrupt(problem);
      job.plan = std::move(plan);
    }
    if (job.phase == JobPhase::kRendering && !job.plan) return corrupt("rendering without a plan");
    if (!q.isNull(6)) {
      const bool films = job.phase == JobPhase::kRendering;
      const size_t values = films ? size_t(job.plan->width) * size_t(job.plan->height) * 3 : 0;
      const uint32_t groups =
          films ? SplatAggregator::groupCount(errorGroupsOf(job.plan->chains)) : 0;
      SplatAggregator::Snapshot snapshot;
      std::string sumsFile;
      if (!store::decodeCheckpoint(q.bytes(6), values, groups, log_.dir(), &snapshot,
                                   &job.checkpointChains, &sumsFile, &problem)) {
        return corrupt(problem);
      }
      if (!sumsFile.empty()) log_.knowFilm(job.id, sumsFile);
      if (job.phase == JobPhase::kRendering &&
          job.checkpointChains.size() != job.plan->chains.size()) {
        return corrupt("a checkpoint of " + std::to_string(job.checkpointChains.size()) +
                       " chains for a plan of " + std::to_string(job.plan->chains.size()));
      }
      job.checkpoint = std::move(snapshot);
    }
    if (job.phase == JobPhase::kRendering) {
      Statement tail(db_, "SELECT offset, length FROM flushes WHERE job = ? ORDER BY seq");
      tail.bind(1, job.id);
      int trc;
      FlushLog::Reader log = log_.reader(job.id);
      std::string record;
      while ((trc = tail.step()) == SQLITE_ROW) {
        if (!log.read(uint64_t(tail.integer(0)), uint64_t(tail.integer(1)), &record)) {
          return corrupt("the flush log " + log_.logPath(job.id) + " ends before a recorded flush");
        }
        FlushBatch batch;
        if (!store::decodeRecord(record, &batch, &problem)) return corrupt(problem);
        job.tail.push_back(std::move(batch));
      }
      if (trc != SQLITE_DONE) return fail("cannot read the flushes of job " + job.id);
    }
    Statement errors(db_,
                     "SELECT elapsed, samples, rmse, relmse, estimated FROM errors WHERE job = ? "
                     "ORDER BY idx");
    errors.bind(1, job.id);
    int erc;
    while ((erc = errors.step()) == SQLITE_ROW) {
      job.errorSeries.push_back(
          {errors.real(0), errors.integer(1), errors.real(2), errors.real(3), errors.real(4)});
    }
    if (erc != SQLITE_DONE) return fail("cannot read the error series of job " + job.id);
    jobs->push_back(std::move(job));
  }
  if (rc != SQLITE_DONE) return fail("cannot read jobs");
  // Checkpoint films no record names: written before a crash kept their record from
  // committing, or left behind by one that kept the previous film from being removed.
  log_.sweep();
  return Status::ok();
}

}  // namespace farm
