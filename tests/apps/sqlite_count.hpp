#pragma once
// A test's independent look into a database file: one integer value of a query, read through a
// fresh read-only SQLite connection of its own (not the project's Database class).

#include <sqlite3.h>

#include <string>

namespace hapticlab {
namespace {

/// The first column of the first row of `sql` on `path`; -1 when the file cannot be read.
/// Waits up to 5 s for a writer's lock.
inline int Count(const std::string& path, const std::string& sql) {
  sqlite3* h = nullptr;
  int n = -1;
  if (sqlite3_open_v2(path.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_busy_timeout(h, 5000);
    sqlite3_stmt* st = nullptr;
    if (sqlite3_prepare_v2(h, sql.c_str(), -1, &st, nullptr) == SQLITE_OK &&
        sqlite3_step(st) == SQLITE_ROW)
      n = sqlite3_column_int(st, 0);
    sqlite3_finalize(st);
  }
  sqlite3_close(h);
  return n;
}

}  // namespace
}  // namespace hapticlab
