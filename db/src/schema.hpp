#pragma once
// Forward migrations of the study record. Migration k takes a file from version k-1 to k.

#include <sqlite3.h>

namespace hapticlab::db::internal {

// Number of migrations (equals kSchemaVersion).
int MigrationCount();
// SQL of migration k (1-based).
const char* MigrationSql(int k);

}  // namespace hapticlab::db::internal
