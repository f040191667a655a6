#include "hapticlab/db/database.hpp"

#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::database_test {
namespace {

TEST(Database, CreatesLatestSchemaFromEmptyFile) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  EXPECT_EQ(db.SchemaVersion(), kSchemaVersion);
  EXPECT_EQ(db.IntegrityCheck(), "ok");
}

TEST(Database, MigratesForwardFromEveryEarlierVersionKeepingData) {
  for (int from = 1; from < kSchemaVersion; ++from) {
    SCOPED_TRACE(from);
    test::TempDir dir;
    {
      Database old(dir.File("a.db"), {.migrate_to = from});
      ASSERT_EQ(old.SchemaVersion(), from);
      test::InsertOneRowEach(old, from);
    }
    Database db(dir.File("a.db"));
    EXPECT_EQ(db.SchemaVersion(), kSchemaVersion);
    const auto studies = db.Studies();
    ASSERT_EQ(studies.size(), 1u);
    const auto p = db.FindParticipant(studies[0].id, "P01");
    ASSERT_TRUE(p.has_value());
    const auto sessions = db.Sessions(p->id);
    ASSERT_EQ(sessions.size(), 1u);
    EXPECT_EQ(sessions[0].plan_json, "[]");  // column added by v3 with its default
    const auto trials = db.Trials(sessions[0].id);
    ASSERT_EQ(trials.size(), 1u);
    const auto ratings = db.Ratings(trials[0].id);
    ASSERT_EQ(ratings.size(), 1u);
    EXPECT_DOUBLE_EQ(ratings[0].score, 61.5);
    // Tables of later versions work after the migration.
    db.SaveMaterialModel("Denim", "[contact]\n");
    db.LogEvent({.session_id = sessions[0].id, .kind = db::EventKind::kResume});
    EXPECT_EQ(db.IntegrityCheck(), "ok");
  }
}

TEST(Database, RefusesFilesFromTheFutureAndForeignFiles) {
  test::TempDir dir;
  {
    Database db(dir.File("a.db"));
    db.Exec("INSERT INTO schema_version(version) VALUES (999)");
  }
  EXPECT_THROW(Database(dir.File("a.db")), std::runtime_error);
  {
    Database other(dir.File("b.db"), {.migrate_to = 0});
    other.Exec("CREATE TABLE foo(x)");
  }
  EXPECT_THROW(Database(dir.File("b.db")), std::runtime_error);
}

TEST(Database, RefusesFilesWhoseTablesAreNotTheSchemaWithoutSql) {
  test::TempDir dir;
  auto refused = [&](const std::string& name, const std::string& sql, const char* expect) {
    const std::string path = dir.File(name);
    {
      Database db(path);
      test::InsertOneRowEach(db, kSchemaVersion);
      db.Exec(sql);
    }
    for (bool reading : {true, false}) {
      try {
        if (reading)
          OpenForReading(path);
        else
          Database d(path);
        ADD_FAILURE() << sql << " was accepted";
      } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(path), std::string::npos) << what;
        EXPECT_NE(what.find(expect), std::string::npos) << what;
        for (const char* raw : {"SELECT", "prepare", "quick_check", "no such table"})
          EXPECT_EQ(what.find(raw), std::string::npos) << what;
      }
    }
  };
  refused("dropped.db", "DROP TABLE rating", "table 'rating' is missing");
  // A migration that cannot run again: the version says 1, the tables are the latest.
  refused("rolled_back.db", "DELETE FROM schema_version WHERE version > 1",
          "do not match it (migration to version 2 failed");
}

TEST(Database, ForeignKeysAreEnforced) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  EXPECT_THROW(db.Exec("INSERT INTO trial(session_id, plan_index, phase, material) "
                       "VALUES (42,0,'main','x')"),
               std::runtime_error);
}

// A v3 file as older builds left it: chunks without attempts, one trial with two attempts'
// chunks mixed (a failed attempt, then a completed one restarting every stream's time).
TEST(Database, MigrationToV4AttributesChunksOrLeavesThemOutOfEveryRead) {
  test::TempDir dir;
  const std::string path = dir.File("old.db");
  {
    Database old(path, {.migrate_to = 3});
    test::InsertOneRowEach(old, 3);  // trial 1: never started, one rating
    old.Exec(
        "INSERT INTO trial(session_id, plan_index, phase, material, status, attempts) VALUES "
        "(1,1,'main','A','completed',1), (1,2,'main','B','completed',2), "
        "(1,3,'main','C','completed',2)");
    auto chunk = [&](int trial, double t0) {
      old.Exec(
          "INSERT INTO trajectory_chunk(trial_id, stream, start_time_s, rate_hz, channels, "
          "sample_count, "
          "samples) VALUES (" +
          std::to_string(trial) + ",'force'," + std::to_string(t0) + ",1000,'fz_N',1,x'0000803f')");
    };
    chunk(2, 0);
    chunk(2, 1);  // trial 2: one attempt, two chunks
    chunk(3, 0);
    chunk(3, 1);
    chunk(3, 0);  // trial 3: the time restarts, a second attempt wrote again: mixed
    chunk(4, 0);
    chunk(4, 1);  // trial 4: two attempts, but only one wrote (no restart)
  }
  Database db(path);
  ASSERT_EQ(db.SchemaVersion(), kSchemaVersion);
  EXPECT_EQ(db.TrajectoryChunks(2).size(), 2u);
  EXPECT_EQ(db.TrajectoryChunks(2)[0].attempt, 1);
  EXPECT_TRUE(db.TrajectoryChunks(3).empty());      // never read with the trial again
  EXPECT_EQ(db.TrajectoryChunks(3, 0).size(), 3u);  // but kept
  EXPECT_EQ(db.TrajectoryChunks(4).size(), 2u);
  EXPECT_EQ(db.TrajectoryChunks(4)[0].attempt, 2);
  int unattributed = 0;
  for (const auto& e : db.Events(1))
    unattributed += e.kind == db::EventKind::kTrajectoryUnattributed && e.trial_id == 3;
  EXPECT_EQ(unattributed, 1);
  EXPECT_EQ(db.IntegrityCheck(), "ok");
}

TEST(Database, OpenForReadingMigratesAnOlderFileFirst) {
  test::TempDir dir;
  const std::string path = dir.File("v3.db");
  {
    Database old(path, {.migrate_to = 3});
    test::InsertOneRowEach(old, 3);
  }
  const Database d = OpenForReading(path);
  EXPECT_EQ(d.SchemaVersion(), kSchemaVersion);
  EXPECT_TRUE(d.TrajectoryChunks(1).empty());  // reads the v4 columns
  EXPECT_TRUE(d.VerifyTrajectories().empty());
}

TEST(Database, ScoresThatAreNotFiniteNumbersAreRefusedOnRead) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  test::InsertOneRowEach(db, kSchemaVersion);
  EXPECT_EQ(db.Ratings(1).size(), 1u);
  for (const char* bad : {"'abc'", "x'00'", "9e999"}) {
    SCOPED_TRACE(bad);
    db.Exec(std::string("UPDATE rating SET score = ") + bad);
    try {
      db.Ratings(1);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("rating.score"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(dir.File("a.db")), std::string::npos) << e.what();
    }
  }
}

TEST(Database, OpenForReadingRefusesDamagedFilesWithAClearMessage) {
  test::TempDir dir;
  const std::string path = dir.File("a.db");
  {
    Database db(path);
    test::InsertOneRowEach(db, kSchemaVersion);
    for (int i = 0; i < 200; ++i)
      db.Exec("INSERT INTO event(session_id, kind, detail) VALUES (1, 'x', '" +
              std::string(400, 'e') + "')");
    db.Exec("PRAGMA wal_checkpoint(TRUNCATE)");
  }
  EXPECT_NO_THROW(OpenForReading(path));
  EXPECT_THROW(OpenForReading(dir.File("missing.db")), InputError);
  // A file of another kind (a protocol given as --db) or a folder is named as such, without
  // SQLite's own words.
  test::WriteFile(dir.File("p.toml"), "[study]\nname = \"x\"\n");
  // A writer refuses it too, and leaves it as it was.
  EXPECT_THROW(Database(dir.File("p.toml")), InputError);
  EXPECT_EQ(test::ReadFile(dir.File("p.toml")), "[study]\nname = \"x\"\n");
  for (const std::string& other : {dir.File("p.toml"), dir.path()}) {
    try {
      OpenForReading(other);
      ADD_FAILURE() << "accepted " << other;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.find("damaged"), std::string::npos) << msg;
      EXPECT_EQ(msg.find("file is not a database"), std::string::npos) << msg;
      EXPECT_TRUE(msg.find("not a SQLite database") != std::string::npos ||
                  msg.find("a folder") != std::string::npos)
          << msg;
    }
  }
  // Overwrite pages in the middle of the file.
  {
    std::string bytes = test::ReadFile(path);
    ASSERT_GT(bytes.size(), 40000u);
    for (std::size_t i = 20000; i < 36000; ++i) bytes[i] = static_cast<char>(i * 7);
    test::WriteFile(path, bytes);
  }
  try {
    OpenForReading(path);
    ADD_FAILURE() << "a damaged file was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("damaged"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hapticlab::db::database_test
