#include "hapticlab/test/sqlite_peek.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <functional>

namespace hapticlab::test {
namespace {

constexpr int kBusyTimeoutMs = 5000;  // a writer's lock, waited for [ms]

// Opens `path` read-only, prepares `sql` and calls `row` for each row; false (and a test
// failure when `strict`) when the file does not open or SQLite refuses the statement.
bool ForEachRow(const std::string& path, const std::string& sql, bool strict,
                const std::function<void(sqlite3_stmt*)>& row) {
  sqlite3* h = nullptr;
  bool ok = sqlite3_open_v2(path.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK;
  if (!ok && strict) ADD_FAILURE() << path << ": " << sqlite3_errmsg(h);
  sqlite3_stmt* s = nullptr;
  if (ok) {
    sqlite3_busy_timeout(h, kBusyTimeoutMs);
    ok = sqlite3_prepare_v2(h, sql.c_str(), -1, &s, nullptr) == SQLITE_OK;
    if (!ok && strict) ADD_FAILURE() << path << ": " << sql << ": " << sqlite3_errmsg(h);
  }
  while (ok && sqlite3_step(s) == SQLITE_ROW) row(s);
  sqlite3_finalize(s);
  sqlite3_close(h);
  return ok;
}

std::string Text(sqlite3_stmt* s, int column) {
  const auto* text = sqlite3_column_text(s, column);
  return text == nullptr ? "NULL" : reinterpret_cast<const char*>(text);
}

}  // namespace

std::vector<std::string> QueryRows(const std::string& path, const std::string& sql) {
  std::vector<std::string> rows;
  ForEachRow(path, sql, true, [&](sqlite3_stmt* s) {
    std::string row;
    for (int c = 0; c < sqlite3_column_count(s); ++c) row += (c > 0 ? "|" : "") + Text(s, c);
    rows.push_back(row);
  });
  return rows;
}

std::string QueryCell(const std::string& path, const std::string& sql) {
  std::optional<std::string> cell;
  ForEachRow(path, sql, true, [&](sqlite3_stmt* s) {
    if (!cell) cell = Text(s, 0);
  });
  return cell.value_or("(no row)");
}

int QueryInt(const std::string& path, const std::string& sql) {
  std::optional<int> n;
  ForEachRow(path, sql, true, [&](sqlite3_stmt* s) {
    if (!n) n = sqlite3_column_int(s, 0);
  });
  return n.value_or(-1);
}

std::optional<int> TryQueryInt(const std::string& path, const std::string& sql) {
  std::optional<int> n;
  ForEachRow(path, sql, false, [&](sqlite3_stmt* s) {
    if (!n) n = sqlite3_column_int(s, 0);
  });
  return n;
}

void ExecSql(const std::string& path, const std::string& sql) {
  sqlite3* h = nullptr;
  if (sqlite3_open(path.c_str(), &h) != SQLITE_OK) {
    ADD_FAILURE() << path << ": " << sqlite3_errmsg(h);
  } else {
    char* error = nullptr;
    if (sqlite3_exec(h, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK)
      ADD_FAILURE() << path << ": " << sql << ": " << (error ? error : "?");
    sqlite3_free(error);
  }
  sqlite3_close(h);
}

}  // namespace hapticlab::test
