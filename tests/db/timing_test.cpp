// Per-side loop timing rows (timing.cpp): 23 columns bound and read by position, so every
// field gets a distinct value and must come back in its own field; a second row for the same
// trial, attempt, side and loop replaces the first; another study's rows stay out.

#include "hapticlab/db/timing.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <utility>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::timing_test {
namespace {

// A study with one participant, session and trial; returns {study id, trial id}.
std::pair<std::int64_t, std::int64_t> OneTrial(Database& db, const std::string& name) {
  const auto r = test::AddStudySession(db, {.name = name, .protocol_toml = "p", .seed = 1});
  return {
      r.study,
      db.AddTrial(
          {.session_id = r.session, .plan_index = 0, .phase = PhaseKind::kMain, .material = "D"})};
}

SideTiming Distinct(std::int64_t trial) {
  return {.trial_id = trial,
          .attempt = 2,
          .side = "left",
          .loop = "force",
          .clock = "real",
          .rate_hz = 1000,
          .achieved_rate_hz = 999.5,
          .ticks = 4003,
          .deadline_misses = 5,
          .late_p50_us = 1.5,
          .late_p99_us = 2.5,
          .late_p999_us = 3.5,
          .late_max_us = 4.5,
          .tick_p50_us = 5.5,
          .tick_p99_us = 6.5,
          .tick_p999_us = 7.5,
          .tick_max_us = 8.5,
          .late_histogram = "0:1,8:2",
          .recording_overflows = 9,
          .audio_underruns = 10,
          .priority = "SCHED_FIFO 80",
          .memory_locked = true,
          .timer_slack_ns = 11};
}

TEST(Timing, EveryFieldRoundTripsIntoItsOwnField) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto [study, trial] = OneTrial(db, "s");
  const SideTiming w = Distinct(trial);
  SaveSideTiming(db, w);
  const auto rows = StudySideTimings(db, study);
  ASSERT_EQ(rows.size(), 1u);
  const auto& r = rows[0];
  EXPECT_EQ(r.trial_id, w.trial_id);
  EXPECT_EQ(r.attempt, w.attempt);
  EXPECT_EQ(r.side, w.side);
  EXPECT_EQ(r.loop, w.loop);
  EXPECT_EQ(r.clock, w.clock);
  EXPECT_EQ(r.rate_hz, w.rate_hz);
  EXPECT_EQ(r.achieved_rate_hz, w.achieved_rate_hz);
  EXPECT_EQ(r.ticks, w.ticks);
  EXPECT_EQ(r.deadline_misses, w.deadline_misses);
  EXPECT_EQ(r.late_p50_us, w.late_p50_us);
  EXPECT_EQ(r.late_p99_us, w.late_p99_us);
  EXPECT_EQ(r.late_p999_us, w.late_p999_us);
  EXPECT_EQ(r.late_max_us, w.late_max_us);
  EXPECT_EQ(r.tick_p50_us, w.tick_p50_us);
  EXPECT_EQ(r.tick_p99_us, w.tick_p99_us);
  EXPECT_EQ(r.tick_p999_us, w.tick_p999_us);
  EXPECT_EQ(r.tick_max_us, w.tick_max_us);
  EXPECT_EQ(r.late_histogram, w.late_histogram);
  EXPECT_EQ(r.recording_overflows, w.recording_overflows);
  EXPECT_EQ(r.audio_underruns, w.audio_underruns);
  EXPECT_EQ(r.priority, w.priority);
  EXPECT_EQ(r.memory_locked, w.memory_locked);
  EXPECT_EQ(r.timer_slack_ns, w.timer_slack_ns);
}

TEST(Timing, ASecondRowForTheSameLoopReplacesTheFirstAndStudiesStayApart) {
  test::TempDir dir;
  Database db(dir.File("a.db"));
  const auto [study, trial] = OneTrial(db, "s");
  const auto [other, other_trial] = OneTrial(db, "t");
  SideTiming a = Distinct(trial);
  SaveSideTiming(db, a);
  a.ticks = 17;
  SaveSideTiming(db, a);  // same trial, attempt, side and loop
  a.loop = "vibration";
  SaveSideTiming(db, a);
  SaveSideTiming(db, Distinct(other_trial));
  const auto rows = StudySideTimings(db, study);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].loop, "force");
  EXPECT_EQ(rows[0].ticks, 17);
  EXPECT_EQ(rows[1].loop, "vibration");
  EXPECT_EQ(StudySideTimings(db, other).size(), 1u);
}

}  // namespace
}  // namespace hapticlab::db::timing_test
