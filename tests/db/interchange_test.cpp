// What the BIDS and XDF exports share (db/src/interchange.cpp): channel meanings from the
// unit suffixes, BIDS labels, the database's time stamps as integers, and the session clock
// that places overlapping (simulated) trials back to back.

#include <gtest/gtest.h>

#include <stdexcept>

#include "../../db/src/interchange_internal.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/test_util.hpp"
#include "interchange_record.hpp"

namespace hapticlab::db::internal::interchange_test {
namespace {

TEST(InterchangeLoad, ChannelUnitsComeFromTheLongestSuffix) {
  EXPECT_EQ(DescribeChannel("acc_mps2").unit, "m/s^2");  // not "m/s" from "_mps"
  EXPECT_EQ(DescribeChannel("vx_mps").unit, "m/s");
  EXPECT_EQ(DescribeChannel("fz_N").unit, "N");
  EXPECT_EQ(DescribeChannel("x_m").unit, "m");
  EXPECT_EQ(DescribeChannel("t_s").unit, "s");
  EXPECT_EQ(DescribeChannel("f_Hz").unit, "Hz");
  EXPECT_EQ(DescribeChannel("contact").unit, "n/a");
  EXPECT_EQ(DescribeChannel("_N").unit, "n/a");  // a suffix alone names no quantity
  // The recorded channels carry their documented meaning; others a generic sentence.
  EXPECT_NE(DescribeChannel("z_m").description.find("normal to the sample surface"),
            std::string::npos);
  EXPECT_NE(DescribeChannel("acc_mps2").description.find("acceleration"), std::string::npos);
  EXPECT_EQ(DescribeChannel("grip_N").description, "force (grip_N)");
  EXPECT_EQ(DescribeChannel("contact").description, "contact (dimensionless)");
}

TEST(InterchangeLoad, LabelsKeepLettersAndDigitsOnly) {
  EXPECT_EQ(Alnum("P-01_a b"), "P01ab");
  EXPECT_EQ(Alnum("Two Words"), "TwoWords");
  EXPECT_EQ(Alnum("--"), "");
}

TEST(InterchangeLoad, StampsAreExactMicrosecondsSince1970) {
  // 2026-01-01T00:00:00Z is 1767225600 s after the epoch (date -u -d ... +%s).
  EXPECT_EQ(ParseUtcMicros("2026-01-01T00:00:00.000Z"), 1767225600LL * 1000000);
  EXPECT_EQ(ParseUtcMicros("1970-01-01T00:00:01.000001Z"), 1000001);
  // Differences of stamps are exact to the microsecond far from the epoch.
  EXPECT_EQ(*ParseUtcMicros("2026-11-22T17:42:55.123457Z") -
                *ParseUtcMicros("2026-11-22T17:42:55.123456Z"),
            1);
  EXPECT_EQ(
      *ParseUtcMicros("2026-03-01T00:00:00.000Z") - *ParseUtcMicros("2026-02-28T23:59:59.500Z"),
      500000);
  EXPECT_FALSE(ParseUtcMicros(""));
  EXPECT_FALSE(ParseUtcMicros("2026-01-01T00:00:00.000"));  // no zone: not UTC
  EXPECT_FALSE(ParseUtcMicros("2026-01-01 00:00:00Z"));
  EXPECT_FALSE(ParseUtcMicros("2026-01-01T00:00:75.0Z"));
}

TEST(InterchangeLoad, RecordingEndAndSampleCount) {
  StreamRecording r{.stream = "left_force", .rate_hz = 100, .channels = {"fz_N"}};
  r.chunks.push_back({.start_time_s = 0, .rate_hz = 100, .channels = {"fz_N"}, .samples = {1, 2}});
  r.chunks.push_back(
      {.start_time_s = 0.5, .rate_hz = 100, .channels = {"fz_N"}, .samples = {1, 2, 3}});
  EXPECT_EQ(r.sample_count(), 5u);
  EXPECT_NEAR(r.end_s(), 0.53, 1e-12);
}

TEST(InterchangeLoad, SessionsPlaceOverlappingTrialsBackToBack) {
  test::TempDir dir;
  Database d(dir.File("i.db"));
  const auto ids = test_record::Fill(d);
  const auto sessions = LoadSessions(d, "");
  ASSERT_EQ(sessions.size(), 1u);
  const auto& s = sessions[0];
  EXPECT_EQ(s.participant.code, "P-01");
  EXPECT_EQ(s.number, 1);
  ASSERT_EQ(s.trials.size(), 2u);  // the faulted trial is not there
  const auto& a = s.trials[0];
  const auto& b = s.trials[1];
  EXPECT_EQ(a.trial.id, ids.a);
  EXPECT_EQ(b.trial.id, ids.b);
  EXPECT_NEAR(a.wall_start_s, 1.0, 1e-12);
  EXPECT_NEAR(b.wall_start_s, 1.01, 1e-12);
  EXPECT_NEAR(a.origin_s, test_record::kTrialAStart_s, 1e-12);
  EXPECT_NEAR(b.origin_s, test_record::kTrialBStart_s, 1e-12);
  EXPECT_NEAR(a.stimulus_s, 0.07, 1e-12);  // left 4 samples, then right 3, at 100 Hz
  EXPECT_NEAR(a.offset_s.at("left_force"), 0, 1e-12);
  EXPECT_NEAR(a.offset_s.at("right_force"), 0.04, 1e-12);
  ASSERT_EQ(b.streams.size(), 1u);
  EXPECT_EQ(b.streams[0].chunks.size(), 2u);
  EXPECT_EQ(b.streams[0].sample_count(), 4u);
  EXPECT_NEAR(b.stimulus_s, 0.06, 1e-12);  // to the end of the chunk after the gap
  ASSERT_EQ(s.event_time_s.size(), 1u);
  EXPECT_NEAR(s.event_time_s[0], test_record::kEvent_s, 1e-9);
}

TEST(InterchangeLoad, UnknownParticipantAndDisagreeingChunksAreRefused) {
  test::TempDir dir;
  Database d(dir.File("i.db"));
  const auto ids = test_record::Fill(d);
  EXPECT_EQ(LoadSessions(d, "P-01").size(), 1u);
  try {
    LoadSessions(d, "P-99");
    ADD_FAILURE() << "an unknown participant was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("P-99"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("i.db"), std::string::npos) << e.what();
  }
  // A chunk of one stream at another rate: the recording has no one clock.
  d.Exec(
      fmt::format("UPDATE trajectory_chunk SET rate_hz = 50 WHERE trial_id = {} AND "
                  "start_time_s > 0",
                  ids.b));
  EXPECT_THROW(LoadSessions(d, ""), std::runtime_error);
  // A session start that is not a stamp.
  Database d2(dir.File("j.db"));
  test_record::Fill(d2);
  d2.Exec("UPDATE session SET started_at='yesterday'");
  EXPECT_THROW(LoadSessions(d2, ""), std::runtime_error);
}

}  // namespace
}  // namespace hapticlab::db::internal::interchange_test
