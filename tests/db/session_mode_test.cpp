// Schema v5 (session mode, rating source), WAL checkpoint and the online backup.

#include <gtest/gtest.h>

#include <filesystem>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/sqlite_peek.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::session_mode_test {
namespace {

namespace fs = std::filesystem;

// Ratings counted by an independent SQLite connection (test::QueryInt), not our Database class.
const char* const kRatings = "SELECT count(*) FROM rating";

// A study with one participant, one session in `device`'s mode and `trials` main trials.
std::int64_t OneSession(Database& db, const Session& mode, int trials) {
  const auto st =
      db.CreateStudy({.name = "s", .protocol_toml = "p", .protocol_hash = "h", .seed = 1});
  const auto p = db.AddParticipant({.study_id = st, .code = "P01", .index = 0, .seed = 2});
  Session se = mode;
  se.participant_id = p;
  const auto session = db.StartSession(se);
  for (int i = 0; i < trials; ++i)
    db.AddTrial(
        {.session_id = session, .plan_index = i, .phase = PhaseKind::kMain, .material = "Denim"});
  return session;
}

// Statuses are enums in the program and their names in the file (the names the schema's CHECK
// and every earlier file use); a status the program does not know is bad input naming the
// file and the column, never a silent default.
TEST(SessionMode, StatusesAreStoredByNameAndReadBackOnce) {
  test::TempDir dir;
  const std::string path = dir.File("a.db");
  Database db(path);
  const auto session = OneSession(db, {.device = "sim", .actuator = "none"}, 1);
  const auto trial = db.Trials(session)[0].id;
  EXPECT_EQ(test::QueryCell(path, "SELECT status FROM session"), "running");
  EXPECT_EQ(test::QueryCell(path, "SELECT status FROM trial"), "planned");
  for (const char* name : {"running", "completed", "aborted", "failed"}) {
    const auto status = FromName(kSessionStatusNames, name);
    ASSERT_TRUE(status.has_value()) << name;
    db.EndSession(session, *status);
    EXPECT_EQ(test::QueryCell(path, "SELECT status FROM session"), name);
    EXPECT_EQ(db.Sessions(1)[0].status, *status) << name;
  }
  db.ReopenSession(session);
  EXPECT_EQ(
      test::QueryCell(path, "SELECT status || '/' || coalesce(ended_at, 'open') FROM session"),
      "running/open");
  for (const char* name : {"planned", "running", "completed", "faulted", "aborted"}) {
    const auto status = FromName(kTrialStatusNames, name);
    ASSERT_TRUE(status.has_value()) << name;
    db.SetTrialStatus(trial, *status);
    EXPECT_EQ(test::QueryCell(path, "SELECT status FROM trial"), name);
    EXPECT_EQ(db.Trials(session)[0].status, *status) << name;
  }
  db.Exec("UPDATE session SET status = 'paused'");
  try {
    (void)db.Sessions(1);
    ADD_FAILURE() << "an unknown session status was read";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    EXPECT_EQ(e.diagnostics()[0].file, path);
    EXPECT_EQ(e.diagnostics()[0].field, "session.status");
    EXPECT_NE(e.diagnostics()[0].message.find("'paused'"), std::string::npos);
  }
}

// Event kinds and trial phases likewise: each kind and phase is stored as its name (the text
// every earlier file holds) and read back as the same value; a name the program does not know
// is bad input naming the file and the column.
TEST(SessionMode, EventKindsAndPhasesAreStoredByNameAndReadBackOnce) {
  test::TempDir dir;
  const std::string path = dir.File("a.db");
  Database db(path);
  const auto session = OneSession(db, {.device = "sim", .actuator = "none"}, 0);
  for (const char* name : {"training", "reference", "main", "staircase", "quest-plus"}) {
    const auto phase = FromName(kPhaseKindNames, name);
    ASSERT_TRUE(phase.has_value()) << name;
    const auto id = db.AddTrial({.session_id = session, .phase = *phase, .material = "D"});
    EXPECT_EQ(test::QueryCell(path, "SELECT phase FROM trial WHERE id = " + std::to_string(id)),
              name);
    EXPECT_EQ(db.Trials(session).back().phase, *phase) << name;
  }
  for (const auto& [kind, name] : kEventKindNames) {
    const auto id = db.LogEvent({.session_id = session, .kind = kind});
    EXPECT_EQ(test::QueryCell(path, "SELECT kind FROM event WHERE id = " + std::to_string(id)),
              name);
    EXPECT_EQ(db.Events(session).back().kind, kind) << name;
  }
  // Names written by every earlier build, the migrations' included, are known.
  for (const char* name :
       {"abort", "attempt-faulted", "break", "break-planned", "consent", "consent-unconfirmed",
        "constraint-relaxed", "device", "device-fault", "interrupted", "mode-change",
        "mode-inferred", "pause", "render-stats", "resume", "samples-placed", "stopped",
        "trajectory-fault", "trajectory-unattributed"})
    EXPECT_TRUE(FromName(kEventKindNames, name).has_value()) << name;
  for (const auto& [sql, column] : {std::pair{"UPDATE trial SET phase = 'warmup'", "trial.phase"},
                                    std::pair{"UPDATE event SET kind = 'note'", "event.kind"}}) {
    db.Exec(sql);
    try {
      (void)(std::string(column) == "trial.phase" ? db.Trials(session).size()
                                                  : db.Events(session).size());
      ADD_FAILURE() << "an unknown " << column << " was read";
    } catch (const InputError& e) {
      ASSERT_EQ(e.diagnostics().size(), 1u);
      EXPECT_EQ(e.diagnostics()[0].file, path);
      EXPECT_EQ(e.diagnostics()[0].field, column);
      EXPECT_NE(e.diagnostics()[0].message.find("expected one of"), std::string::npos);
    }
  }
}

// An event whose writer forgot its kind is refused, not stored as the enum's first kind (a
// false 'consent' in the audit trail); nothing reaches the table.
TEST(SessionMode, AnEventWithoutItsKindIsRefusedAndNothingIsStored) {
  test::TempDir dir;
  const std::string path = dir.File("a.db");
  Database db(path);
  const auto session = OneSession(db, {.device = "sim", .actuator = "none"}, 0);
  const auto before = db.Events(session).size();
  EXPECT_THROW(db.LogEvent({.session_id = session, .detail = "forgot the kind"}),
               PreconditionError);
  EXPECT_EQ(db.Events(session).size(), before);
  EXPECT_EQ(test::QueryCell(path, "SELECT count(*) FROM event WHERE detail = 'forgot the kind'"),
            "0");
  EXPECT_TRUE(NameOf(kEventKindNames, EventKind::kUnnamed).empty());
}

TEST(SessionMode, MigrationToV5InfersTheModeFromTheDeviceAndSaysSo) {
  test::TempDir dir;
  const std::string path = dir.File("v4.db");
  {
    Database old(path, {.migrate_to = 4});
    test::InsertTwoSessions(old, "sim", "falcon");
    old.Exec(
        "INSERT INTO trial(session_id, plan_index, phase, material) VALUES (1,0,'main','A'), "
        "(2,0,'main','A')");
    old.Exec(
        "INSERT INTO rating(trial_id, criterion, score, response_time_s) VALUES "
        "(1,'overall',50,1), "
        "(2,'overall',60,1)");
  }
  Database db(path);
  ASSERT_EQ(db.SchemaVersion(), kSchemaVersion);
  const auto s1 = db.Sessions(1).at(0), s2 = db.Sessions(2).at(0);
  EXPECT_EQ(s1.rater, "simulated");
  EXPECT_FALSE(s1.screens);
  EXPECT_EQ(s2.rater, "window");  // a hardware session always rated in the participant window
  EXPECT_TRUE(s2.screens);
  EXPECT_EQ(s1.actuator, "unrecorded");
  EXPECT_EQ(db.Ratings(1).at(0).source, "simulated");
  EXPECT_EQ(db.Ratings(2).at(0).source, "window");
  int inferred = 0;
  for (const auto& e : db.Events(2))
    inferred +=
        e.kind == db::EventKind::kModeInferred && e.detail.find("falcon") != std::string::npos;
  EXPECT_EQ(inferred, 1);
}

TEST(SessionMode, RatingsTakeTheSessionsRaterUnlessTheyNameTheirSource) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto session =
      OneSession(db, {.device = "sim", .actuator = "none", .screens = true, .rater = "window"}, 3);
  const auto trials = db.Trials(session);
  db.StartTrial(trials[0].id);
  db.CompleteTrial(trials[0].id, {{"overall", 40, 1.5, ""}});
  db.StartTrial(trials[1].id);
  db.CompleteTrial(trials[1].id, {{"overall", 41, 1.5, "simulated"}});
  db.SetSessionMode(session, "falcon-twin", "none", false, "simulated");
  db.StartTrial(trials[2].id);
  db.CompleteTrial(trials[2].id, {{"overall", 42, 1.5, ""}});
  EXPECT_EQ(db.Ratings(trials[0].id).at(0).source, "window");
  EXPECT_EQ(db.Ratings(trials[1].id).at(0).source, "simulated");
  EXPECT_EQ(db.Ratings(trials[2].id).at(0).source, "simulated");
  const auto se = db.Sessions(db.Participants(1).at(0).id).at(0);
  EXPECT_EQ(se.device, "falcon-twin");
  EXPECT_FALSE(se.screens);
}

TEST(SessionMode, CheckpointLeavesEveryCommittedRatingInTheMainFile) {
  test::TempDir dir;
  const std::string path = dir.File("a.db");
  Database db(path);
  const auto session = OneSession(db, {.device = "sim"}, 5);
  for (const auto& t : db.Trials(session)) {
    db.StartTrial(t.id);
    db.CompleteTrial(t.id, {{"overall", 50, 1, ""}});
  }
  // Before the checkpoint the ratings may sit in the -wal only; after it, a copy of the main
  // file alone (no -wal beside it) holds them all.
  ASSERT_TRUE(db.Checkpoint());
  EXPECT_EQ(fs::file_size(path + "-wal"), 0u);
  fs::copy_file(path, dir.File("copy.db"));
  EXPECT_EQ(test::QueryInt(dir.File("copy.db"), kRatings), 5);
}

TEST(SessionMode, OnlineBackupCopiesTheWalAndNeverOverwrites) {
  test::TempDir dir;
  const std::string path = dir.File("a.db");
  Database db(path);
  const auto session = OneSession(db, {.device = "sim"}, 4);
  for (const auto& t : db.Trials(session)) {
    db.StartTrial(t.id);
    db.CompleteTrial(t.id, {{"overall", 50, 1, ""}, {"roughness", 20, 1, ""}});
  }
  // The writer keeps its connection open (a live study): the ratings are in the -wal.
  ASSERT_GT(fs::file_size(path + "-wal"), 0u);
  db.Backup(dir.File("b.db"));
  EXPECT_FALSE(fs::exists(dir.File("b.db-wal")) && fs::file_size(dir.File("b.db-wal")) > 0);
  EXPECT_EQ(test::QueryInt(dir.File("b.db"), kRatings), 8);
  EXPECT_EQ(Database(dir.File("b.db"), {.create = false, .read_only = true}).IntegrityCheck(),
            "ok");
  // An existing destination is refused and left alone.
  const auto before = fs::file_size(dir.File("b.db"));
  EXPECT_THROW(db.Backup(dir.File("b.db")), InputError);
  EXPECT_EQ(fs::file_size(dir.File("b.db")), before);
  // A destination in a folder that does not exist is named as such, not in SQLite's words.
  try {
    db.Backup(dir.File("no-such-folder/c.db"));
    ADD_FAILURE() << "backed up into a missing folder";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("no-such-folder does not exist"), std::string::npos) << msg;
    EXPECT_EQ(msg.find("unable to open"), std::string::npos) << msg;
  }
}

}  // namespace
}  // namespace hapticlab::db::session_mode_test
