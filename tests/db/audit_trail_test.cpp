// Schema v7 (each event names who or what established it) on old files, and the writer lease
// leaving no host name behind.

#include <gtest/gtest.h>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/sqlite_peek.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::audit_trail_test {
namespace {

// Rows of writer_lease, counted by an independent SQLite connection (test::QueryInt).
const char* const kLeaseRows = "SELECT count(*) FROM writer_lease";

TEST(AuditTrail, MigrationToV7MarksTheUnconfirmedConsentAndEveryOlderEvent) {
  test::TempDir dir;
  const std::string path = dir.File("v6.db");
  {
    Database old(path, {.migrate_to = 6});
    test::InsertTwoSessions(old, "falcon", "sim");
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
    EXPECT_EQ(test::QueryInt(path, kLeaseRows), 1) << "held: named for a second writer";
  }
  EXPECT_EQ(test::QueryInt(path, kLeaseRows), 0);
  {
    const WriterLease again(path);  // the next writer takes it as before
    EXPECT_EQ(test::QueryInt(path, kLeaseRows), 1);
  }
  EXPECT_EQ(test::QueryInt(path, kLeaseRows), 0);
}

}  // namespace
}  // namespace hapticlab::db::audit_trail_test
