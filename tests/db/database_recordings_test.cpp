#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::database_recordings_test {
namespace {

TEST(Database, StoresModelsEventsAndChunks) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto a = db.SaveMaterialModel("Cork", "[contact]\nK_N_per_m = 1\n");
  EXPECT_EQ(db.SaveMaterialModel("Cork", "[contact]\nK_N_per_m = 1\n"), a);  // same hash
  EXPECT_NE(db.SaveMaterialModel("Cork", "[contact]\nK_N_per_m = 2\n"), a);
  const auto se = test::AddStudySession(db).session;
  const auto t = db.AddTrial({.session_id = se, .phase = PhaseKind::kMain, .material = "Cork"});
  db.LogEvent(
      {.session_id = se, .trial_id = t, .kind = db::EventKind::kDeviceFault, .detail = "stale"});
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

}  // namespace
}  // namespace hapticlab::db::database_recordings_test
