#include "coordinator/job_store.h"

#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>

#include "proto/splat_codec.h"
#include "proto/zstd_frame.h"

namespace farm {
namespace fs = std::filesystem;

namespace {

// The schema's version in meta('schema'): a database of another version is refused, not guessed.
// 2: flush records live in DIR/logs/<job>.log; the flushes table holds where.
// 3: errors.estimated, the error estimated without a reference (a version-2 database is
//    brought to 3 on opening: its jobs have one error group and no estimate).
// 4: flush records hold their flushes as the wire's FlushEntry (coordinator/store_records.h);
//    a version-3 database is marked 4 on opening, its records of the older forms still read.
constexpr int64_t kSchemaVersion = 4;

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS meta(key TEXT PRIMARY KEY, value INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS bundles(hash TEXT PRIMARY KEY, manifest BLOB NOT NULL);
CREATE TABLE IF NOT EXISTS jobs(
  ord INTEGER PRIMARY KEY AUTOINCREMENT,
  id TEXT UNIQUE NOT NULL,
  spec BLOB NOT NULL,
  phase INTEGER NOT NULL,
  error TEXT NOT NULL DEFAULT '',
  elapsed REAL NOT NULL DEFAULT 0,
  tail_bytes INTEGER NOT NULL DEFAULT 0);
-- Large records in tables of their own: SQLite rewrites a whole row on UPDATE, and a job's row
-- changes with every flush.
CREATE TABLE IF NOT EXISTS plans(job TEXT PRIMARY KEY, record BLOB NOT NULL);
CREATE TABLE IF NOT EXISTS checkpoints(job TEXT PRIMARY KEY, record BLOB NOT NULL);
CREATE TABLE IF NOT EXISTS flushes(
  job TEXT NOT NULL, seq INTEGER NOT NULL, offset INTEGER NOT NULL, length INTEGER NOT NULL,
  PRIMARY KEY(job, seq));
CREATE TABLE IF NOT EXISTS errors(
  job TEXT NOT NULL, idx INTEGER NOT NULL, elapsed REAL NOT NULL, samples INTEGER NOT NULL,
  rmse REAL NOT NULL, relmse REAL NOT NULL, estimated REAL NOT NULL DEFAULT -1,
  PRIMARY KEY(job, idx));
)sql";

// One prepared statement; finalized on every path out.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) : db_(db) {
    if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) stmt_ = nullptr;
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  bool ok() const { return stmt_ != nullptr; }
  Statement& bind(int i, const std::string& text) {
    sqlite3_bind_text(stmt_, i, text.data(), int(text.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Statement& blob(int i, const std::string& bytes) {
    sqlite3_bind_blob64(stmt_, i, bytes.data(), bytes.size(), SQLITE_TRANSIENT);
    return *this;
  }
  Statement& bind(int i, int64_t v) {
    sqlite3_bind_int64(stmt_, i, v);
    return *this;
  }
  Statement& bind(int i, double v) {
    sqlite3_bind_double(stmt_, i, v);
    return *this;
  }
  Statement& null(int i) {
    sqlite3_bind_null(stmt_, i);
    return *this;
  }
  // SQLITE_ROW, SQLITE_DONE or an error code.
  int step() { return stmt_ ? sqlite3_step(stmt_) : SQLITE_ERROR; }
  bool run() { return step() == SQLITE_DONE; }
  int64_t integer(int col) const { return sqlite3_column_int64(stmt_, col); }
  double real(int col) const { return sqlite3_column_double(stmt_, col); }
  bool isNull(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }
  std::string bytes(int col) const {
    const void* data = sqlite3_column_blob(stmt_, col);
    const int size = sqlite3_column_bytes(stmt_, col);
    return data ? std::string(static_cast<const char*>(data), size_t(size)) : std::string();
  }

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

template <class T>
std::string compressVector(const std::vector<T>& values) {
  return zstdCompress(values.data(), values.size() * sizeof(T));
}

// Whether a job id can name files in DIR/logs (its log and its checkpoint films).
bool namesAFile(const std::string& id) {
  return !id.empty() && id.find('/') == std::string::npos && id.find("..") == std::string::npos;
}

// All of `bytes` at `offset` of `fd`, through short writes and interruptions; false with errno
// set when the system refuses.
bool writeFully(int fd, const std::string& bytes, uint64_t offset) {
  for (size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::pwrite(fd, bytes.data() + done, bytes.size() - done, off_t(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += size_t(n);
  }
  return true;
}

}  // namespace

JobStore::JobStore(sqlite3* db, std::string path, std::string logDir)
    : db_(db), path_(std::move(path)), logDir_(std::move(logDir)) {}

JobStore::~JobStore() {
  for (auto& [id, log] : logs_) ::close(log.fd);
  sqlite3_close(db_);
}

std::string JobStore::logPath(const std::string& id) const {
  return (fs::path(logDir_) / (id + ".log")).string();
}

Status JobStore::openLogLocked(const std::string& id, FlushLog** out) {
  auto it = logs_.find(id);
  if (it != logs_.end()) {
    *out = &it->second;
    return Status::ok();
  }
  if (!namesAFile(id)) return Status::invalidArgument("job id '" + id + "' cannot name a log file");
  // Bytes past the last committed record are a flush whose commit never happened (a crash
  // between the append and the commit, or a failed commit): cut them off.
  Statement q(db_, "SELECT IFNULL(MAX(offset + length), 0) FROM flushes WHERE job = ?");
  q.bind(1, id);
  if (q.step() != SQLITE_ROW) return fail("cannot read the log of job " + id);
  const int64_t end = q.integer(0);
  const std::string path = logPath(id);
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0 || ::ftruncate(fd, off_t(end)) != 0) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) ::close(fd);
    return Status::internal("cannot open the flush log " + path + ": " + why);
  }
  FlushLog& log = logs_[id];
  log.fd = fd;
  log.end = uint64_t(end);
  *out = &log;
  return Status::ok();
}

void JobStore::resetLogLocked(const std::string& id) {
  // After a commit that dropped every row of the log: its bytes are garbage now, and the next
  // open would cut them off anyway.
  auto it = logs_.find(id);
  if (it != logs_.end()) {
    if (::ftruncate(it->second.fd, 0) == 0) it->second.end = 0;
    ::close(it->second.fd);
    logs_.erase(it);
  }
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
  if (Status st = s->exec(kSchema); !st.isOk()) return st;
  int64_t schema = kSchemaVersion;
  Status st = s->transaction("cannot initialize", [&] {
    Statement version(db, "INSERT OR IGNORE INTO meta(key, value) VALUES('schema', ?)");
    Statement read(db, "SELECT value FROM meta WHERE key = 'schema'");
    Statement bump(db,
                   "INSERT INTO meta(key, value) VALUES('generation', 1) "
                   "ON CONFLICT(key) DO UPDATE SET value = value + 1 RETURNING value");
    if (!version.bind(1, kSchemaVersion).run() || read.step() != SQLITE_ROW) return false;
    schema = read.integer(0);
    if (schema == 2) {
      Statement column(db, "ALTER TABLE errors ADD COLUMN estimated REAL NOT NULL DEFAULT -1");
      Statement mark(db, "UPDATE meta SET value = 3 WHERE key = 'schema'");
      if (!column.run() || !mark.run()) return false;
      schema = 3;
    }
    if (schema == 3) {
      Statement mark(db, "UPDATE meta SET value = 4 WHERE key = 'schema'");
      if (!mark.run()) return false;
      schema = 4;
    }
    if (schema != kSchemaVersion) return false;
    if (bump.step() != SQLITE_ROW) return false;
    s->generation_ = uint64_t(bump.integer(0));
    return bump.step() == SQLITE_DONE;
  });
  if (schema != kSchemaVersion) {
    return Status::failedPrecondition("coordinator database " + path + " has schema version " +
                                      std::to_string(schema) + "; this coordinator reads " +
                                      std::to_string(kSchemaVersion));
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
    if (!finalCounts->sums.empty()) {
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
  if (st.isOk() && isTerminal(phase)) {
    resetLogLocked(id);
    std::error_code ec;
    fs::remove(logPath(id), ec);
    if (auto it = sumsFiles_.find(id); it != sumsFiles_.end()) {
      fs::remove(fs::path(logDir_) / it->second, ec);
      sumsFiles_.erase(it);
    }
  }
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
  FlushLog* log = nullptr;
  if (Status st = openLogLocked(id, &log); !st.isOk()) return st;
  // The record goes beside the database, on disk before the row that points at it is
  // committed: a flush's bytes are written once (a blob in SQLite's WAL is written twice, page
  // by page), and a crash between the two leaves bytes that no row points at.
  if (!writeFully(log->fd, record, log->end) || ::fdatasync(log->fd) != 0) {
    return Status::internal(what + ": " + logPath(id) + ": " + std::strerror(errno));
  }
  int64_t tail = 0;
  Status st = transaction(what, [&] {
    if (!Statement(db_,
                   "INSERT INTO flushes(job, seq, offset, length) VALUES(?1, "
                   "(SELECT IFNULL(MAX(seq), 0) + 1 FROM flushes WHERE job = ?1), ?2, ?3)")
             .bind(1, id)
             .bind(2, int64_t(log->end))
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
  log->end += record.size();
  if (tailBytes) *tailBytes = uint64_t(tail);
  return st;
}

Status JobStore::checkpoint(const std::string& id, const SplatAggregator::Snapshot& sums,
                            const std::vector<ChainScheduler::ChainSnapshot>& chains) {
  if (!namesAFile(id)) return Status::invalidArgument("job id '" + id + "' cannot name a file");
  const std::string frame = compressVector(sums.sums);  // outside the lock
  std::lock_guard<std::mutex> lock(mutex_);
  // The film goes beside the database, written once (a blob would go through the WAL, twice),
  // under a name of its own: on disk, under its final name, before the record that names it
  // commits; the previous film is removed only after. A crash in between leaves a file that no
  // record names, which the next open removes.
  const std::string name =
      id + "." + std::to_string(generation_) + "." + std::to_string(++sumsWritten_) + ".sums";
  const std::string path = (fs::path(logDir_) / name).string();
  if (Status st = writeDurably(path, frame); !st.isOk()) return st;
  const std::string record = store::encodeCheckpoint(sums, chains, name);
  Status st = transaction("cannot checkpoint job " + id, [&] {
    return Statement(db_, "INSERT OR REPLACE INTO checkpoints(job, record) VALUES(?, ?)")
               .bind(1, id)
               .blob(2, record)
               .run() &&
           Statement(db_, "UPDATE jobs SET tail_bytes = 0 WHERE id = ?").bind(1, id).run() &&
           Statement(db_, "DELETE FROM flushes WHERE job = ?").bind(1, id).run();
  });
  std::error_code ec;
  if (!st.isOk()) {
    fs::remove(path, ec);
    return st;
  }
  resetLogLocked(id);
  auto previous = sumsFiles_.find(id);
  if (previous != sumsFiles_.end() && previous->second != name) {
    fs::remove(fs::path(logDir_) / previous->second, ec);
  }
  sumsFiles_[id] = name;
  return st;
}

Status JobStore::writeDurably(const std::string& path, const std::string& bytes) {
  const std::string temporary = path + ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Status::internal("cannot write " + temporary + ": " + std::strerror(errno));
  if (!writeFully(fd, bytes, 0)) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    return Status::internal("cannot write " + temporary + ": " + why);
  }
  if (::fdatasync(fd) != 0 || ::close(fd) != 0 || ::rename(temporary.c_str(), path.c_str()) != 0) {
    return Status::internal("cannot write " + path + ": " + std::strerror(errno));
  }
  // The rename is durable once the directory is.
  const int dir = ::open(logDir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  const bool synced = dir >= 0 && ::fsync(dir) == 0;
  if (dir >= 0) ::close(dir);
  if (!synced) return Status::internal("cannot sync " + logDir_ + ": " + std::strerror(errno));
  return Status::ok();
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
      const size_t values =
          job.phase == JobPhase::kRendering
              ? size_t(SplatAggregator::groupCount(errorGroupsOf(job.plan->chains))) *
                    size_t(job.plan->width) * size_t(job.plan->height) * 3
              : 0;
      SplatAggregator::Snapshot snapshot;
      std::string sumsFile;
      if (!store::decodeCheckpoint(q.bytes(6), values, logDir_, &snapshot, &job.checkpointChains,
                                   &sumsFile, &problem)) {
        return corrupt(problem);
      }
      if (!sumsFile.empty()) sumsFiles_[job.id] = sumsFile;
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
      std::ifstream log;
      std::string record;
      while ((trc = tail.step()) == SQLITE_ROW) {
        if (!log.is_open()) log.open(logPath(job.id), std::ios::binary);
        record.resize(size_t(tail.integer(1)));
        if (!log.seekg(std::streamoff(tail.integer(0))) ||
            !log.read(record.data(), std::streamsize(record.size()))) {
          return corrupt("the flush log " + logPath(job.id) + " ends before a recorded flush");
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
  std::set<std::string> named;
  for (const auto& [job, file] : sumsFiles_) named.insert(file);
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(logDir_, ec)) {
    const std::string file = e.path().filename().string();
    const bool film = e.path().extension() == ".sums" ||
                      (e.path().extension() == ".tmp" && e.path().stem().extension() == ".sums");
    if (film && !named.count(file)) fs::remove(e.path(), ec);
  }
  return Status::ok();
}

}  // namespace farm
