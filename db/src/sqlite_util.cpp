#include "sqlite_util.hpp"

#include <stdexcept>

namespace hapticlab::db::internal {

std::string Explain(int code) {
  switch (code & 0xff) {
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB:
      return "the database file is damaged or not a database; restore it from a backup (or "
             "try 'sqlite3 FILE .recover' on a copy)";
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
      return "another process held the database locked for longer than the busy timeout";
    case SQLITE_FULL:
      return "the disk is full; free space and resume";
    case SQLITE_READONLY:
      return "the database (or its -wal/-shm file, or its folder) is not writable";
    case SQLITE_CANTOPEN:
      return "the database (or its -wal/-shm file) cannot be opened";
    case SQLITE_IOERR:
      return "an I/O error occurred on the database file";
    case SQLITE_NOMEM:
      return "out of memory";
    default:
      return "";
  }
}

void ThrowSqlite(sqlite3* db, const std::string& what) {
  const char* file = db ? sqlite3_db_filename(db, "main") : nullptr;
  const std::string plain = db ? Explain(sqlite3_extended_errcode(db)) : "";
  throw std::runtime_error((file && *file ? std::string(file) + ": " : std::string()) +
                           (plain.empty() ? what : plain + " (" + what + ")") + ": " +
                           (db ? sqlite3_errmsg(db) : "no connection"));
}

Stmt::Stmt(sqlite3* db, const char* sql) : db_(db) {
  if (sqlite3_prepare_v2(db, sql, -1, &s_, nullptr) != SQLITE_OK)
    // The statement's text stays out of the message (users read it); a prepare fails on a file
    // whose tables are not this build's (Database checks the shape when it opens a file).
    ThrowSqlite(db, "a query on the study record");
}
Stmt::~Stmt() { sqlite3_finalize(s_); }

Stmt& Stmt::Bind(int i, std::int64_t v) {
  if (sqlite3_bind_int64(s_, i, v) != SQLITE_OK) ThrowSqlite(db_, "bind");
  return *this;
}
Stmt& Stmt::Bind(int i, double v) {
  if (sqlite3_bind_double(s_, i, v) != SQLITE_OK) ThrowSqlite(db_, "bind");
  return *this;
}
Stmt& Stmt::Bind(int i, const std::string& v) {
  if (sqlite3_bind_text(s_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT) != SQLITE_OK)
    ThrowSqlite(db_, "bind");
  return *this;
}
Stmt& Stmt::BindNull(int i) {
  if (sqlite3_bind_null(s_, i) != SQLITE_OK) ThrowSqlite(db_, "bind");
  return *this;
}
Stmt& Stmt::BindBlob(int i, const void* data, std::size_t bytes) {
  if (sqlite3_bind_blob64(s_, i, data, bytes, SQLITE_TRANSIENT) != SQLITE_OK)
    ThrowSqlite(db_, "bind");
  return *this;
}
bool Stmt::Step() {
  const int rc = sqlite3_step(s_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  ThrowSqlite(db_, "step");
}
void Stmt::Run() {
  while (Step()) {
  }
}
void Stmt::Reset() {
  sqlite3_reset(s_);
  sqlite3_clear_bindings(s_);
}
std::string Stmt::Text(int col) const {
  const auto* p = sqlite3_column_text(s_, col);
  return p ? std::string(reinterpret_cast<const char*>(p),
                         static_cast<std::size_t>(sqlite3_column_bytes(s_, col)))
           : std::string();
}

void ExecSql(sqlite3* db, const char* sql) {
  char* err = nullptr;
  if (const int rc = sqlite3_exec(db, sql, nullptr, nullptr, &err); rc != SQLITE_OK) {
    std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    const std::string plain = Explain(sqlite3_extended_errcode(db));
    (void)sql;  // not in the message: users read it
    throw std::runtime_error(std::string(sqlite3_db_filename(db, "main")) + ": " +
                             (plain.empty() ? "" : plain + ": ") + msg);
  }
}

}  // namespace hapticlab::db::internal

namespace hapticlab::db {

WriteTransaction::WriteTransaction(sqlite3* db) : db_(db) {
  internal::ExecSql(db_, "BEGIN IMMEDIATE");
}
WriteTransaction::WriteTransaction(Database& database) : WriteTransaction(database.handle()) {}
WriteTransaction::~WriteTransaction() {
  if (!done_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
}
void WriteTransaction::Commit() {
  internal::ExecSql(db_, "COMMIT");
  done_ = true;
}

}  // namespace hapticlab::db
