#pragma once
// The coordinator database's tables (JobStore, job_store.h): what each holds, their versions and
// how an older database is brought to this one, and the prepared statement everything reads and
// writes them through. The records in the BLOB columns are store_records.h's.
#include <sqlite3.h>

#include <cstdint>
#include <string>

namespace farm::store {

// The schema's version in meta('schema'): a database of another version is refused, not guessed.
// 2: flush records live in DIR/logs/<job>.log; the flushes table holds where.
// 3: errors.estimated, the error estimated without a reference (a version-2 database is
//    brought to 3 on opening: its jobs have one error group and no estimate).
// 4: flush records hold their flushes as the wire's FlushEntry (coordinator/store_records.h);
//    a version-3 database is marked 4 on opening, its records of the older forms still read.
constexpr int64_t kSchemaVersion = 4;

// Creates the tables a new database lacks (every table, IF NOT EXISTS); an SQLite error: false,
// with *error saying why.
bool createTables(sqlite3* db, std::string* error);

// Within the caller's transaction: records kSchemaVersion in a new database, or brings one of an
// older version to it. *version: the database's version now (kSchemaVersion, or one this
// coordinator does not read). False on an SQLite error or an unknown version.
bool migrate(sqlite3* db, int64_t* version);

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

}  // namespace farm::store
