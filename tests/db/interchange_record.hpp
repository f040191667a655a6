#pragma once
// A small study record made through the db API with fixed time stamps, shared by the tests
// of the interchange loader and the BIDS and XDF exports (tests/db/interchange_test.cpp,
// export_bids_test.cpp, export_xdf_test.cpp).
//
// Study "Two Words", participant "P-01", one session started at 10:00:00.000Z:
// - trial A (plan 0, stamped 10:00:01.000Z): left_force 100 Hz {fz_N, vx_mps}, 4 samples;
//   right_force 100 Hz {fz_N}, 3 samples; rating roughness 60 after 0.5 s.
// - trial B (plan 1, stamped 10:00:01.010Z, overlapping A): left_force 100 Hz {fz_N, vx_mps},
//   2 samples at 0 s and 2 more at 0.04 s (2 samples dropped between); rating 30 after 0.25 s.
// - trial C (plan 2): recorded 5 samples, then faulted (never exported).
// - an event "break" stamped 10:00:01.020Z (0.010 s after B's stamp).
// On the session clock (interchange_internal.hpp): A starts at 1.0 and occupies
// 0.04 + 0.03 s of stimuli + 0.5 s of rating, so B starts at 1.57, its stamp (1.01) being
// earlier; the event keeps its 0.010 s from B's start: 1.58.

#include <fmt/format.h>

#include <cstdint>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/study_rows.hpp"

namespace hapticlab::db::test_record {

inline constexpr double kTrialAStart_s = 1.0;
inline constexpr double kTrialBStart_s = 1.57;
inline constexpr double kEvent_s = 1.58;

struct Ids {
  std::int64_t a = 0, b = 0, faulted = 0;
};

inline Ids Fill(Database& d) {
  const auto se =
      test::AddStudySession(d, {.name = "Two Words", .protocol_toml = "# p", .seed = 1}, "P-01")
          .session;
  const auto ids = test::AddTrials(d, {{.session_id = se,
                                        .plan_index = 0,
                                        .phase = PhaseKind::kMain,
                                        .material = "Cork",
                                        .comparison = "virtual",
                                        .method = "FF",
                                        .left = "real:Cork",
                                        .right = "virtual:Cork"},
                                       {.session_id = se,
                                        .plan_index = 1,
                                        .phase = PhaseKind::kMain,
                                        .material = "Denim",
                                        .comparison = "virtual",
                                        .method = "FF",
                                        .left = "virtual:Denim",
                                        .right = "real:Denim"},
                                       {.session_id = se,
                                        .plan_index = 2,
                                        .phase = PhaseKind::kMain,
                                        .material = "Towel",
                                        .comparison = "virtual",
                                        .method = "FF"}});
  Ids out{ids[0], ids[1], ids[2]};
  d.StartTrial(out.a);
  d.InsertTrajectoryChunk({.trial_id = out.a,
                           .stream = "left_force",
                           .rate_hz = 100,
                           .channels = {"fz_N", "vx_mps"},
                           .samples = {1, -1, 2, -2, 3, -3, 4, -4},
                           .attempt = 1});
  d.InsertTrajectoryChunk({.trial_id = out.a,
                           .stream = "right_force",
                           .rate_hz = 100,
                           .channels = {"fz_N"},
                           .samples = {5, 6, 7},
                           .attempt = 1});
  d.CompleteTrial(out.a, {{"roughness", 60, 0.5}});
  d.StartTrial(out.b);
  d.InsertTrajectoryChunk({.trial_id = out.b,
                           .stream = "left_force",
                           .rate_hz = 100,
                           .channels = {"fz_N", "vx_mps"},
                           .samples = {10, 0.5f, 11, 0.25f},
                           .attempt = 1});
  d.InsertTrajectoryChunk({.trial_id = out.b,
                           .stream = "left_force",
                           .start_time_s = 0.04,
                           .rate_hz = 100,
                           .channels = {"fz_N", "vx_mps"},
                           .samples = {14, 0.125f, 15, 0.0625f},
                           .attempt = 1});
  d.CompleteTrial(out.b, {{"roughness", 30, 0.25}});
  d.StartTrial(out.faulted);
  d.InsertTrajectoryChunk({.trial_id = out.faulted,
                           .stream = "left_force",
                           .rate_hz = 100,
                           .channels = {"fz_N", "vx_mps"},
                           .samples = {99, 99, 99, 99, 99, 99, 99, 99, 99, 99},
                           .attempt = 1});
  d.SetTrialStatus(out.faulted, TrialStatus::kFaulted);
  d.LogEvent({.session_id = se, .kind = db::EventKind::kBreak, .detail = "pause"});
  d.Exec("UPDATE session SET started_at='2026-01-01T10:00:00.000Z'");
  d.Exec(fmt::format("UPDATE trial SET started_at='2026-01-01T10:00:01.000Z' WHERE id={}", out.a));
  d.Exec(fmt::format("UPDATE trial SET started_at='2026-01-01T10:00:01.010Z' WHERE id={}", out.b));
  d.Exec("UPDATE event SET created_at='2026-01-01T10:00:01.020Z' WHERE kind='break'");
  return out;
}

}  // namespace hapticlab::db::test_record
