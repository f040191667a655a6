// Schema v7 (each event names who or what established it) on old files, and the writer lease
// leaving no host name behind.

#include <gtest/gtest.h>
#include <sqlite3.h>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::audit_trail_test {
namespace {

// Rows of writer_lease, counted by an independent SQLite connection.
int LeaseRows(const std::string& path) {
  sqlite3* h = nullptr;
  EXPECT_EQ(sqlite3_open_v2(path.c_str(), &h, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* s = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(h, "SELECT count(*) FROM writer_lease", -1, &s, nullptr), SQLITE_OK)
      << sqlite3_errmsg(h);
  int n = -1;
  if (sqlite3_step(s) == SQLITE_ROW) n = sqlite3_column_int(s, 0);
  sqlite3_finalize(s);
  sqlite3_close(h);
  return n;
}

TEST(AuditTrail, MigrationToV7MarksTheUnconfirmedConsentAndEveryOlderEvent) {
  test::TempDir dir;
  const std::string path = dir.File("v6.db");
  {
    Database old(path, {.migrate_to = 6});
    old.Exec("INSERT INTO study(name, protocol_toml, protocol_hash, seed) VALUES ('s','p','h',7)");
    old.Exec(
        "INSERT INTO participant(study_id, code, idx, seed) VALUES (1,'P01',0,11), (1,'P02',1,12)");
    old.Exec("INSERT INTO session(participant_id, device) VALUES (1,'falcon'), (2,'sim')");
    // What earlier builds wrote at every session start, and a fault.
    old.Exec(
        "INSERT INTO event(session_id, kind, detail) VALUES (1,'consent','consent form signed'), "
        "(1,'device-fault','stale at 0.300 s (left side, tick 300)'), "
        "(2,'consent','simulated participant')");
  }
  Database db(path);
  ASSERT_EQ(db.SchemaVersion(), kSchemaVersion);
  const auto e1 = db.Events(1);
  ASSERT_EQ(e1.size(), 3u);
  EXPECT_EQ(e1[0].kind, db::EventKind::kConsent);
  EXPECT_EQ(e1[0].detail, "consent form signed") << "the record is not rewritten";
  EXPECT_EQ(e1[0].established_by.rfind("nobody", 0), 0u) << e1[0].established_by;
  EXPECT_EQ(e1[1].established_by, "unrecorded (before schema v7)");
  EXPECT_EQ(e1[2].kind, db::EventKind::kConsentUnconfirmed);
  EXPECT_EQ(e1[2].established_by, "hapticlab:migration");
  const auto e2 = db.Events(2);
  ASSERT_EQ(e2.size(), 1u) << "a simulated session's consent needs no note";
  EXPECT_EQ(e2[0].established_by, "hapticlab:session-mode");
  // New events carry their source; an empty one is stored as hapticlab's.
  db.LogEvent({.session_id = 2, .kind = db::EventKind::kResume, .detail = "x"});
  db.LogEvent(
      {.session_id = 2, .kind = db::EventKind::kPause, .established_by = "experimenter:console"});
  const auto now = db.Events(2);
  EXPECT_EQ(now[1].established_by, "hapticlab");
  EXPECT_EQ(now[2].established_by, "experimenter:console");
}

TEST(AuditTrail, TheWriterLeaseLeavesNoHostNameWhenItEnds) {
  test::TempDir dir;
  const std::string path = dir.File("l.db");
  {
    const WriterLease lease(path);
    EXPECT_EQ(LeaseRows(path), 1) << "held: named for a second writer";
  }
  EXPECT_EQ(LeaseRows(path), 0);
  {
    const WriterLease again(path);  // the next writer takes it as before
    EXPECT_EQ(LeaseRows(path), 1);
  }
  EXPECT_EQ(LeaseRows(path), 0);
}

}  // namespace
}  // namespace hapticlab::db::audit_trail_test
