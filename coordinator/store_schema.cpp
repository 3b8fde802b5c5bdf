#include "coordinator/store_schema.h"

namespace farm::store {

namespace {

constexpr const char* kTables = R"sql(
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

}  // namespace

bool createTables(sqlite3* db, std::string* error) {
  char* message = nullptr;
  if (sqlite3_exec(db, kTables, nullptr, nullptr, &message) == SQLITE_OK) return true;
  *error = message ? message : "unknown error";
  sqlite3_free(message);
  return false;
}

bool migrate(sqlite3* db, int64_t* version) {
  Statement insert(db, "INSERT OR IGNORE INTO meta(key, value) VALUES('schema', ?)");
  Statement read(db, "SELECT value FROM meta WHERE key = 'schema'");
  if (!insert.bind(1, kSchemaVersion).run() || read.step() != SQLITE_ROW) return false;
  int64_t schema = read.integer(0);
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
  *version = schema;
  return schema == kSchemaVersion;
}

}  // namespace farm::store
