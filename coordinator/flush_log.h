#pragma once
// The files of the coordinator's store beside its database (DIR/logs): each rendering job's
// append-only log of accepted flushes (<job>.log) and the film of its newest checkpoint
// (<job>.<generation>.<n>.sums). The database's rows say which bytes count (JobStore, in the
// same transaction as everything else it records); this class only writes, syncs, cuts and
// removes files, in the order that keeps them consistent with those rows across a crash:
//
//  - A record is written and synced at the log's end before the row that points at it commits,
//    and the end moves past it only once it has (commit()). A crash or a failed commit in
//    between leaves bytes no row points at: the next write overwrites them, the next open cuts
//    them off.
//  - A film is written under a fresh name by way of a temporary file, synced and renamed, before
//    the record that names it commits; the film it replaces is removed only after (adopt()).
//    A crash in between leaves a film no record names, which sweep() removes.
//
// Why files and not blobs: SQLite writes a blob twice (WAL, then the database) a page at a time,
// which made a 1080p flush cost 0.6 s of the coordinator's time against 0.16 s in memory
// (tests/farm_load.cpp). Not thread-safe: JobStore calls it under its own lock.
#include <cstdint>
#include <fstream>
#include <map>
#include <string>

#include "coordinator/status.h"

namespace farm {

class FlushLog {
 public:
  explicit FlushLog(std::string dir);  // DIR/logs, which exists
  ~FlushLog();
  FlushLog(const FlushLog&) = delete;
  FlushLog& operator=(const FlushLog&) = delete;

  const std::string& dir() const { return dir_; }
  // Whether a job id can name files here (no separators, no "..").
  static bool namesAFile(const std::string& id);
  std::string logPath(const std::string& id) const;

  // A job's log, for appending.
  bool isOpen(const std::string& id) const { return open_.count(id) > 0; }
  // Opens the job's log, cut at `committedEnd` (the end of the last record a committed row
  // points at: bytes past it are a flush whose commit never happened).
  Status open(const std::string& id, uint64_t committedEnd);
  // Writes `record` at the end of the job's open log and syncs it; *offset: where it went.
  Status write(const std::string& id, const std::string& record, uint64_t* offset);
  // The row pointing at the record just written committed: the end moves past it.
  void commit(const std::string& id, uint64_t bytes);
  // Every row of the job's log was dropped (a checkpoint folded it): its bytes are garbage now.
  // Truncates and closes it; the next append opens it again.
  void reset(const std::string& id);

  // Reads a job's records on restart, one file handle for the whole tail.
  class Reader {
   public:
    explicit Reader(std::string path) : path_(std::move(path)) {}
    // False where the log ends before offset + length.
    bool read(uint64_t offset, uint64_t length, std::string* record);

   private:
    std::string path_;
    std::ifstream in_;
  };
  Reader reader(const std::string& id) const { return Reader(logPath(id)); }

  // A checkpoint's film: `bytes` under a fresh name (*name, within dir()), synced and renamed
  // into place, the directory synced: all of it or none of it is there after a crash.
  Status writeFilm(const std::string& id, uint64_t generation, const std::string& bytes,
                   std::string* name);
  // A film whose record did not commit.
  void discardFilm(const std::string& name);
  // The record naming `name` committed: it is the job's film, and the one before is removed.
  void adoptFilm(const std::string& id, const std::string& name);
  // On restart: the film the job's stored checkpoint names.
  void knowFilm(const std::string& id, const std::string& name) { films_[id] = name; }
  // The job ended: its log and its film go.
  void removeJob(const std::string& id);
  // Removes the films no job's checkpoint names (and their temporary files): left by a crash
  // before their record committed, or after it but before the one they replaced was removed.
  void sweep();

 private:
  struct Open {
    int fd = -1;
    uint64_t end = 0;  // where the next record goes: the end of the last committed one
  };
  std::string dir_;
  std::map<std::string, Open> open_;
  std::map<std::string, std::string> films_;  // job -> its checkpoint's film
  uint64_t filmsWritten_ = 0;
};

}  // namespace farm
