#pragma once
// A test's independent look into a database file: SQLite's own C API on a fresh connection of
// the test's (not the project's Database class), opened, used and closed per call. The
// read-only calls wait up to 5 s for a writer's lock.

#include <optional>
#include <string>
#include <vector>

namespace hapticlab::test {

/// Every row of `sql` on `path`, each row's columns joined by '|' (NULL as "NULL"). A file
/// that does not open or a statement SQLite refuses is a test failure (and no rows).
std::vector<std::string> QueryRows(const std::string& path, const std::string& sql);

/// The first column of the first row of `sql` as text: "(no row)" when there is none, "NULL"
/// for a NULL. Failures as QueryRows.
std::string QueryCell(const std::string& path, const std::string& sql);

/// The first column of the first row of `sql` as an integer (a count, a sum); -1 when there
/// is no row. Failures as QueryRows.
int QueryInt(const std::string& path, const std::string& sql);

/// QueryInt for a file that may not hold the answer yet (a process still creating it): no
/// value, and no test failure, when the file does not open, the statement is refused (a table
/// not made yet) or there is no row.
std::optional<int> TryQueryInt(const std::string& path, const std::string& sql);

/// Runs `sql` (any number of statements) on `path` read-write, creating the file if needed:
/// another program's hand on the file. A failure is a test failure naming SQLite's message.
void ExecSql(const std::string& path, const std::string& sql);

}  // namespace hapticlab::test
