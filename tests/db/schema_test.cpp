// The study record's schema (schema.cpp), read back by SQLite itself through its own C API
// (not our Database class): every foreign key names a parent key SQLite can enforce, and no
// migration leaves a row pointing at nothing.

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/sqlite_peek.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::schema_test {
namespace {

// SQLite checks a foreign key's parent only when a row is written ("foreign key mismatch",
// sqlite.org/foreignkeys.html §3): the parent key must be the parent's primary key or carry a
// UNIQUE index. Each single-column key is checked here for every table of a fresh file.
TEST(Schema, EveryForeignKeyReferencesAPrimaryOrUniqueKey) {
  test::TempDir dir;
  const auto path = dir.File("a.db");
  { Database db(path); }
  const auto tables = test::QueryRows(path, "SELECT name FROM sqlite_master WHERE type = 'table'");
  ASSERT_GE(tables.size(), 5u);
  int keys = 0;
  for (const auto& table : tables) {
    // id|seq|table|from|to|on_update|on_delete|match
    for (const auto& fk : test::QueryRows(
             path, "SELECT \"table\", \"to\" FROM pragma_foreign_key_list('" + table + "')")) {
      ++keys;
      const auto bar = fk.find('|');
      const std::string parent = fk.substr(0, bar), to = fk.substr(bar + 1);
      SCOPED_TRACE(table + " -> " + parent + "(" + to + ")");
      const auto pk = test::QueryRows(
          path, "SELECT name FROM pragma_table_info('" + parent + "') WHERE pk > 0");
      ASSERT_FALSE(
          test::QueryRows(path, "SELECT name FROM sqlite_master WHERE type = 'table' AND name = '" +
                                    parent + "'")
              .empty())
          << "parent table missing";
      if (to == "NULL") {  // REFERENCES parent: its primary key
        EXPECT_EQ(pk.size(), 1u);
        continue;
      }
      std::set<std::string> unique;  // single-column keys only
      if (pk.size() == 1) unique.insert(pk[0]);
      for (const auto& index : test::QueryRows(
               path, "SELECT name FROM pragma_index_list('" + parent + "') WHERE \"unique\" = 1")) {
        const auto cols =
            test::QueryRows(path, "SELECT name FROM pragma_index_info('" + index + "')");
        if (cols.size() == 1) unique.insert(cols[0]);
      }
      EXPECT_TRUE(unique.count(to) == 1) << "parent key is neither primary nor unique";
    }
  }
  EXPECT_GE(keys, 5);  // trial -> session -> participant -> study, rating -> trial, ...
}

// Migration 9 removes the measurement table (no production writer): a version-8 file has it,
// the migrated file does not, and a fresh file never gets it.
TEST(Schema, TheMeasurementTableIsGoneAfterMigration9) {
  test::TempDir dir;
  const auto path = dir.File("old.db");
  const std::string kTables =
      "SELECT name FROM sqlite_master WHERE type='table' AND name='measurement'";
  { Database old(path, {.migrate_to = 8}); }
  EXPECT_EQ(test::QueryRows(path, kTables), std::vector<std::string>{"measurement"});
  { Database db(path); }
  EXPECT_EQ(test::QueryRows(path, kTables), std::vector<std::string>{});
  const auto fresh = dir.File("new.db");
  { Database db(fresh); }
  EXPECT_EQ(test::QueryRows(fresh, kTables), std::vector<std::string>{});
}

// Migrations rewrite rows (attempt numbers, rating sources, events): after each one, SQLite's
// own checks find no dangling foreign key and an intact file.
TEST(Schema, MigratedFilesPassSqlitesForeignKeyAndIntegrityChecks) {
  for (int from = 1; from < kSchemaVersion; ++from) {
    SCOPED_TRACE(from);
    test::TempDir dir;
    const auto path = dir.File("a.db");
    {
      Database old(path, {.migrate_to = from});
      test::InsertOneRowEach(old, from);
    }
    { Database db(path); }
    EXPECT_EQ(test::QueryRows(path, "PRAGMA foreign_key_check"), std::vector<std::string>{});
    EXPECT_EQ(test::QueryRows(path, "PRAGMA integrity_check"), std::vector<std::string>{"ok"});
    EXPECT_EQ(test::QueryRows(path, "SELECT count(*) FROM rating"), std::vector<std::string>{"1"});
  }
}

}  // namespace
}  // namespace hapticlab::db::schema_test
