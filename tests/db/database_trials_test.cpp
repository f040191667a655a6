#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::database_trials_test {
namespace {

TEST(Database, CompleteTrialStoresRatingsAndMarkerOnce) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto se = test::AddStudySession(db).session;
  const auto ids = test::AddTrials(
      db, {{.session_id = se, .plan_index = 0, .phase = PhaseKind::kMain, .material = "Cork"},
           {.session_id = se, .plan_index = 1, .phase = PhaseKind::kMain, .material = "Denim"}});
  db.StartTrial(ids[0]);
  db.CompleteTrial(ids[0], {{"roughness", 70, 1.5}, {"overall", 65, 2.5}});
  auto trials = db.Trials(se);
  EXPECT_EQ(trials[0].status, TrialStatus::kCompleted);
  EXPECT_EQ(trials[0].attempts, 1);
  EXPECT_EQ(trials[1].status, TrialStatus::kPlanned);
  EXPECT_EQ(db.Ratings(ids[0]).size(), 2u);
  // A second completion is refused and leaves the first intact.
  EXPECT_THROW(db.CompleteTrial(ids[0], {{"hardness", 10, 1}}), std::runtime_error);
  EXPECT_EQ(db.Ratings(ids[0]).size(), 2u);
  // A failing rating (duplicate criterion) rolls back the whole trial.
  EXPECT_THROW(db.CompleteTrial(ids[1], {{"overall", 1, 1}, {"overall", 2, 1}}),
               std::runtime_error);
  EXPECT_TRUE(db.Ratings(ids[1]).empty());
  EXPECT_EQ(db.Trials(se)[1].status, TrialStatus::kPlanned);
}

TEST(Database, CompletionVerifiesEveryStreamAndStoresNothingWhenOneIsNotWhole) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto se = test::AddStudySession(db).session;
  const auto t = db.AddTrial({.session_id = se, .phase = PhaseKind::kMain, .material = "Cork"});
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
  EXPECT_NE(db.Trials(se)[0].status, TrialStatus::kCompleted);
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

}  // namespace
}  // namespace hapticlab::db::database_trials_test
