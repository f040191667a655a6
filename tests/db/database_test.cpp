#include "hapticlab/db/database.hpp"

#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db {
namespace {

// Fills the tables that exist at schema `version` with one row each.
void Populate(Database& db, int version) {
  db.Exec("INSERT INTO study(name, protocol_toml, protocol_hash, seed) VALUES ('s','p','h',7)");
  db.Exec("INSERT INTO participant(study_id, code, idx, seed) VALUES (1,'P01',0,11)");
  db.Exec("INSERT INTO session(participant_id) VALUES (1)");
  db.Exec("INSERT INTO trial(session_id, plan_index, phase, material) VALUES (1,0,'main','Denim')");
  db.Exec(
      "INSERT INTO rating(trial_id, criterion, score, response_time_s) VALUES "
      "(1,'overall',61.5,2.0)");
  if (version >= 2) db.Exec("INSERT INTO event(session_id, kind) VALUES (1,'break')");
}

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
      Populate(old, from);
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
    db.LogEvent({.session_id = sessions[0].id, .kind = "resume"});
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

TEST(Database, ForeignKeysAreEnforced) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  EXPECT_THROW(db.Exec("INSERT INTO trial(session_id, plan_index, phase, material) "
                       "VALUES (42,0,'main','x')"),
               std::runtime_error);
}

TEST(Database, ParticipantCodesMustBePseudonymous) {
  EXPECT_TRUE(IsPseudonymousCode("P07"));
  EXPECT_TRUE(IsPseudonymousCode("lab2-s_14"));
  EXPECT_FALSE(IsPseudonymousCode("Alice"));
  EXPECT_FALSE(IsPseudonymousCode("Alice Smith 1"));
  EXPECT_FALSE(IsPseudonymousCode(""));
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto study = db.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1});
  EXPECT_THROW(db.AddParticipant({.study_id = study, .code = "Alice"}), InputError);
  EXPECT_NO_THROW(db.AddParticipant({.study_id = study, .code = "P01"}));
}

TEST(Database, CompleteTrialStoresRatingsAndMarkerOnce) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto st = db.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1});
  const auto p = db.AddParticipant({.study_id = st, .code = "P01"});
  const auto se = db.StartSession({.participant_id = p});
  const auto ids =
      db.AddTrials({{.session_id = se, .plan_index = 0, .phase = "main", .material = "Cork"},
                    {.session_id = se, .plan_index = 1, .phase = "main", .material = "Denim"}});
  db.StartTrial(ids[0]);
  db.CompleteTrial(ids[0], {{"roughness", 70, 1.5}, {"overall", 65, 2.5}});
  auto trials = db.Trials(se);
  EXPECT_EQ(trials[0].status, kTrialCompleted);
  EXPECT_EQ(trials[0].attempts, 1);
  EXPECT_EQ(trials[1].status, kTrialPlanned);
  EXPECT_EQ(db.Ratings(ids[0]).size(), 2u);
  // A second completion is refused and leaves the first intact.
  EXPECT_THROW(db.CompleteTrial(ids[0], {{"hardness", 10, 1}}), std::runtime_error);
  EXPECT_EQ(db.Ratings(ids[0]).size(), 2u);
  // A failing rating (duplicate criterion) rolls back the whole trial.
  EXPECT_THROW(db.CompleteTrial(ids[1], {{"overall", 1, 1}, {"overall", 2, 1}}),
               std::runtime_error);
  EXPECT_TRUE(db.Ratings(ids[1]).empty());
  EXPECT_EQ(db.Trials(se)[1].status, kTrialPlanned);
}

TEST(Database, StoresModelsMeasurementsEventsAndChunks) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto a = db.SaveMaterialModel("Cork", "[contact]\nK_N_per_m = 1\n");
  EXPECT_EQ(db.SaveMaterialModel("Cork", "[contact]\nK_N_per_m = 1\n"), a);  // same hash
  EXPECT_NE(db.SaveMaterialModel("Cork", "[contact]\nK_N_per_m = 2\n"), a);
  EXPECT_GT(db.SaveMeasurement("Cork", "t_s\n0\n", "{}"), 0);
  const auto st = db.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1});
  const auto p = db.AddParticipant({.study_id = st, .code = "P01"});
  const auto se = db.StartSession({.participant_id = p});
  const auto t = db.AddTrial({.session_id = se, .phase = "main", .material = "Cork"});
  db.LogEvent({.session_id = se, .trial_id = t, .kind = "device-fault", .detail = "stale"});
  ASSERT_EQ(db.Events(se).size(), 1u);
  EXPECT_EQ(*db.Events(se)[0].trial_id, t);
  TrajectoryChunk c{.trial_id = t,
                    .stream = "force",
                    .start_time_s = 1.25,
                    .rate_hz = 1000,
                    .channels = {"x_m", "fz_N"},
                    .samples = {1.f, 2.f, 3.f, 4.f, 5.f, 6.f}};
  db.InsertTrajectoryChunk(c);
  const auto back = db.TrajectoryChunks(t);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].channels, c.channels);
  EXPECT_EQ(back[0].samples, c.samples);
  EXPECT_EQ(back[0].sample_count(), 3u);
  EXPECT_EQ(HashText("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

// A v3 file as older builds left it: chunks without attempts, one trial with two attempts'
// chunks mixed (a failed attempt, then a completed one restarting every stream's time).
TEST(Database, MigrationToV4AttributesChunksOrLeavesThemOutOfEveryRead) {
  test::TempDir dir;
  const std::string path = dir.File("old.db");
  {
    Database old(path, {.migrate_to = 3});
    Populate(old, 3);  // trial 1: never started, one rating
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
    unattributed += e.kind == "trajectory-unattributed" && e.trial_id == 3;
  EXPECT_EQ(unattributed, 1);
  EXPECT_EQ(db.IntegrityCheck(), "ok");
}

TEST(Database, OpenForReadingMigratesAnOlderFileFirst) {
  test::TempDir dir;
  const std::string path = dir.File("v3.db");
  {
    Database old(path, {.migrate_to = 3});
    Populate(old, 3);
  }
  const Database d = OpenForReading(path);
  EXPECT_EQ(d.SchemaVersion(), kSchemaVersion);
  EXPECT_TRUE(d.TrajectoryChunks(1).empty());  // reads the v4 columns
  EXPECT_TRUE(d.VerifyTrajectories().empty());
}

TEST(Database, CompletionVerifiesEveryStreamAndStoresNothingWhenOneIsNotWhole) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto st = db.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1});
  const auto p = db.AddParticipant({.study_id = st, .code = "P01"});
  const auto se = db.StartSession({.participant_id = p});
  const auto t = db.AddTrial({.session_id = se, .phase = "main", .material = "Cork"});
  EXPECT_EQ(db.StartTrial(t), 1);
  EXPECT_EQ(db.StartTrial(t), 2);
  // Attempt 1 left a chunk behind; attempt 2 wrote 3 samples of "force".
  db.InsertTrajectoryChunk({.trial_id = t,
                            .stream = "force",
                            .rate_hz = 1000,
                            .channels = {"fz_N"},
                            .samples = {9, 9},
                            .attempt = 1});
  db.InsertTrajectoryChunk({.trial_id = t,
                            .stream = "force",
                            .rate_hz = 1000,
                            .channels = {"fz_N"},
                            .samples = {1, 2, 3},
                            .attempt = 2});
  StreamReport ok{.trial_id = t,
                  .attempt = 2,
                  .stream = "force",
                  .rate_hz = 1000,
                  .samples_offered = 4,
                  .samples_dropped = 1,
                  .samples_written = 3};
  StreamReport lost = ok;
  lost.samples_dropped = 0;  // 4 queued, 3 written: one chunk lost
  EXPECT_THROW(db.CompleteTrial(t, {{"overall", 50, 1}}, {lost}), TrajectoryIncomplete);
  StreamReport missing{.trial_id = t,
                       .attempt = 2,
                       .stream = "vibration",
                       .rate_hz = 10000,
                       .samples_offered = 5,
                       .samples_written = 5};  // writer says 5, db has none
  EXPECT_THROW(db.CompleteTrial(t, {{"overall", 50, 1}}, {ok, missing}), TrajectoryIncomplete);
  EXPECT_TRUE(db.Ratings(t).empty());
  EXPECT_NE(db.Trials(se)[0].status, kTrialCompleted);
  // A report of an earlier attempt is ignored; the unreported stream "force" then fails.
  StreamReport old = ok;
  old.attempt = 1;
  EXPECT_THROW(db.CompleteTrial(t, {{"overall", 50, 1}}, {old}), TrajectoryIncomplete);
  db.CompleteTrial(t, {{"overall", 50, 1}}, {ok, old});
  ASSERT_EQ(db.Trials(se)[0].completed_attempt, 2);
  ASSERT_EQ(db.TrajectoryChunks(t).size(), 1u);
  EXPECT_EQ(db.TrajectoryChunks(t)[0].samples, (std::vector<float>{1, 2, 3}));
  ASSERT_EQ(db.StreamChecks(t).size(), 1u);
  EXPECT_EQ(db.StreamChecks(t)[0].samples_written, 3u);
  EXPECT_TRUE(db.VerifyTrajectories().empty());
  // Damage after completion is found: a chunk deleted, or a stream added.
  db.Exec("DELETE FROM trajectory_chunk WHERE attempt = 2");
  ASSERT_EQ(db.VerifyTrajectories().size(), 1u);
  EXPECT_NE(db.VerifyTrajectories()[0].find("stream force"), std::string::npos);
  db.InsertTrajectoryChunk({.trial_id = t,
                            .stream = "force",
                            .rate_hz = 1000,
                            .channels = {"fz_N"},
                            .samples = {1, 2, 3},
                            .attempt = 2});
  db.InsertTrajectoryChunk({.trial_id = t,
                            .stream = "extra",
                            .rate_hz = 1000,
                            .channels = {"fz_N"},
                            .samples = {1},
                            .attempt = 2});
  ASSERT_EQ(db.VerifyTrajectories().size(), 1u);
  EXPECT_NE(db.VerifyTrajectories()[0].find("stream extra"), std::string::npos);
}

TEST(Database, ScoresThatAreNotFiniteNumbersAreRefusedOnRead) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  Populate(db, kSchemaVersion);
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
    Populate(db, kSchemaVersion);
    for (int i = 0; i < 200; ++i)
      db.Exec("INSERT INTO event(session_id, kind, detail) VALUES (1, 'x', '" +
              std::string(400, 'e') + "')");
    db.Exec("PRAGMA wal_checkpoint(TRUNCATE)");
  }
  EXPECT_NO_THROW(OpenForReading(path));
  EXPECT_THROW(OpenForReading(dir.File("missing.db")), InputError);
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
}  // namespace hapticlab::db
