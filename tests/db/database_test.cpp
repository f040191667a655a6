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
  db.Exec("INSERT INTO rating(trial_id, criterion, score, response_time_s) VALUES (1,'overall',61.5,2.0)");
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
  const auto ids = db.AddTrials({{.session_id = se, .plan_index = 0, .phase = "main", .material = "Cork"},
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
  EXPECT_THROW(db.CompleteTrial(ids[1], {{"overall", 1, 1}, {"overall", 2, 1}}), std::runtime_error);
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
  TrajectoryChunk c{.trial_id = t, .stream = "force", .start_time_s = 1.25, .rate_hz = 1000,
                    .channels = {"x_m", "fz_N"}, .samples = {1.f, 2.f, 3.f, 4.f, 5.f, 6.f}};
  db.InsertTrajectoryChunk(c);
  const auto back = db.TrajectoryChunks(t);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].channels, c.channels);
  EXPECT_EQ(back[0].samples, c.samples);
  EXPECT_EQ(back[0].sample_count(), 3u);
  EXPECT_EQ(HashText("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

}  // namespace
}  // namespace hapticlab::db
