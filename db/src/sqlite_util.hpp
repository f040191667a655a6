#pragma once
// Thin RAII helpers over the SQLite C API (private to the db module).

#include <sqlite3.h>

#include <cstdint>
#include <string>

#include "hapticlab/db/database.hpp"

namespace hapticlab::db::internal {

// A plain-language explanation of an SQLite result code ("" when it has none).
std::string Explain(int code);
[[noreturn]] void ThrowSqlite(sqlite3* db, const std::string& what);

// A prepared statement; binds are 1-based as in SQLite.
class Stmt {
 public:
  Stmt(sqlite3* db, const char* sql);
  ~Stmt();
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;

  Stmt& Bind(int i, std::int64_t v);
  Stmt& Bind(int i, int v) { return Bind(i, static_cast<std::int64_t>(v)); }
  Stmt& Bind(int i, double v);
  Stmt& Bind(int i, const std::string& v);
  Stmt& BindNull(int i);
  Stmt& BindBlob(int i, const void* data, std::size_t bytes);
  // Steps once: true when a row is available, false when done. Throws on error.
  bool Step();
  // Steps to completion (statements without rows).
  void Run();
  void Reset();

  std::int64_t Int(int col) const { return sqlite3_column_int64(s_, col); }
  double Real(int col) const { return sqlite3_column_double(s_, col); }
  std::string Text(int col) const;
  bool IsNull(int col) const { return sqlite3_column_type(s_, col) == SQLITE_NULL; }
  bool IsNumber(int col) const {
    const int t = sqlite3_column_type(s_, col);
    return t == SQLITE_INTEGER || t == SQLITE_FLOAT;
  }
  const void* Blob(int col) const { return sqlite3_column_blob(s_, col); }
  int BlobBytes(int col) const { return sqlite3_column_bytes(s_, col); }

 private:
  sqlite3* db_;
  sqlite3_stmt* s_ = nullptr;
};

// db::WriteTransaction on a bare connection (BEGIN IMMEDIATE ... COMMIT, rolled back when
// destroyed uncommitted).
class Transaction : public WriteTransaction {
 public:
  explicit Transaction(sqlite3* db) : WriteTransaction(db) {}
};

void ExecSql(sqlite3* db, const char* sql);

}  // namespace hapticlab::db::internal
