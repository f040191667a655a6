// The XDF export (db/src/export_xdf.cpp) read back by libxdf (Debian's libxdf-dev), a reader
// this project did not write: one stream per recorded stream with its channels' units, every
// timestamp on the session clock, trial starts and ratings as markers, and the file-or-folder
// choice of the output. InterchangeRecord: a record with a dropped-sample gap, a stored model
// and overlapping stamps, exported to XDF (libxdf) and to BIDS (the official bids-validator).

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <xdf.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/interchange.hpp"
#include "hapticlab/test/bids.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"
#include "interchange_record.hpp"

namespace hapticlab::db::export_xdf_test {
namespace {

namespace tr = test_record;
namespace fs = std::filesystem;
using nlohmann::json;

TEST(ExportXdf, StreamsAndMarkersOnTheSessionClock) {
  test::TempDir dir;
  Database d(dir.File("x.db"));
  tr::Fill(d);
  const auto files = ExportXdf(d, dir.File("s.xdf"));
  ASSERT_EQ(files.size(), 1u);
  // 8 + 3 samples of trial A, 4 of B (the faulted trial's 5 are not exported), 3 events
  // (two trial starts and the break), 2 ratings.
  EXPECT_EQ(files[0].samples, 4u + 3u + 4u + 3u + 2u);
  EXPECT_EQ(files[0].rows, 0u);  // a binary file has streams and samples, not rows
  Xdf x;
  ASSERT_EQ(x.load_xdf(dir.File("s.xdf")), 0);
  std::map<std::string, const Xdf::Stream*> by;
  for (const auto& s : x.streams) by[s.info.name] = &s;
  ASSERT_EQ(by.size(), 4u);
  EXPECT_EQ(files[0].streams, x.streams.size());
  const auto& left = *by.at("left_force");
  EXPECT_EQ(left.info.channel_count, 2);
  EXPECT_EQ(left.info.nominal_srate, 100);
  EXPECT_EQ(left.info.type, "Force");
  EXPECT_NE(left.streamHeader.find("<label>vx_mps</label><unit>m/s</unit>"), std::string::npos)
      << left.streamHeader;
  EXPECT_NE(left.streamHeader.find("<participant>P-01</participant>"), std::string::npos);
  // Trial A at 1.0 s; trial B at 1.57 s (after A's stimuli and rating), with its second
  // chunk 0.04 s into the stimulus (two samples dropped before it).
  const std::vector<double> t_left = {1.0, 1.01, 1.02, 1.03, 1.57, 1.58, 1.61, 1.62};
  const std::vector<float> fz = {1, 2, 3, 4, 10, 11, 14, 15};
  ASSERT_EQ(left.time_stamps.size(), t_left.size());
  for (std::size_t i = 0; i < t_left.size(); ++i) {
    EXPECT_NEAR(left.time_stamps[i], t_left[i], 1e-9) << i;
    EXPECT_EQ(left.time_series[0][i], fz[i]) << i;
  }
  EXPECT_EQ(left.time_series[1][1], -2.0f);
  EXPECT_EQ(left.time_series[1][7], 0.0625f);
  // The right stimulus follows the left one (4 samples at 100 Hz).
  const auto& right = *by.at("right_force");
  ASSERT_EQ(right.time_stamps.size(), 3u);
  EXPECT_NEAR(right.time_stamps[0], 1.04, 1e-9);
  EXPECT_EQ(right.time_series[0][2], 7.0f);

  std::vector<std::pair<double, json>> events, ratings;
  for (const auto& [ev, stream] : x.eventMap) {
    auto& list =
        x.streams[static_cast<std::size_t>(stream)].info.name == "ratings" ? ratings : events;
    list.emplace_back(ev.second, json::parse(ev.first));
  }
  ASSERT_EQ(events.size(), 3u);
  ASSERT_EQ(ratings.size(), 2u);
  std::map<int, double> start_of;
  double break_at = -1;
  for (const auto& [t, j] : events) {
    if (j["marker"] == "trial_start") start_of[j["trial"].get<int>() - 1] = t;
    if (j["marker"] == "event" && j["kind"] == "break") break_at = t;
  }
  EXPECT_NEAR(start_of.at(0), tr::kTrialAStart_s, 1e-9);
  EXPECT_NEAR(start_of.at(1), tr::kTrialBStart_s, 1e-9);
  EXPECT_NEAR(break_at, tr::kEvent_s, 1e-9);
  // Ratings at the stimuli's end + the response time: 1.0 + 0.07 + 0.5, 1.57 + 0.06 + 0.25.
  std::map<int, std::pair<double, double>> rating_of;
  for (const auto& [t, j] : ratings)
    rating_of[j["trial"].get<int>() - 1] = {t, j["score"].get<double>()};
  EXPECT_NEAR(rating_of.at(0).first, 1.57, 1e-9);
  EXPECT_EQ(rating_of.at(0).second, 60);
  EXPECT_NEAR(rating_of.at(1).first, 1.88, 1e-9);
  EXPECT_EQ(rating_of.at(1).second, 30);
}

TEST(ExportXdf, AFileHoldsOneSessionAndAFolderOnePerSession) {
  test::TempDir dir;
  Database d(dir.File("x.db"));
  tr::Fill(d);
  const auto study = d.FindStudy("Two Words");
  ASSERT_TRUE(study);
  const auto p2 = d.AddParticipant({.study_id = study->id, .code = "P02", .index = 1});
  d.StartSession({.participant_id = p2});
  try {
    ExportXdf(d, dir.File("both.xdf"));
    ADD_FAILURE() << "two sessions were written into one file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("both.xdf"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("has 2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ExportXdf(d, dir.File("x.xdf"), "P99"), InputError);
  EXPECT_EQ(ExportXdf(d, dir.File("p2.xdf"), "P02").size(), 1u);
  const auto files = ExportXdf(d, dir.File("all"));
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(std::filesystem::path(files[0].path).filename(), "sub-P-01_ses-1_task-TwoWords.xdf");
  EXPECT_EQ(std::filesystem::path(files[1].path).filename(), "sub-P02_ses-1_task-TwoWords.xdf");
  // The session without trials still has its marker streams, empty.
  Xdf x;
  ASSERT_EQ(x.load_xdf(files[1].path), 0);
  EXPECT_EQ(x.streams.size(), 2u);
  EXPECT_TRUE(x.eventMap.empty());
}

// A record made through the db API with fixed time stamps: a dropped-sample gap inside a
// recording, a stored material model, trials whose stamps overlap (as in a simulated
// session) and one that starts later (as on hardware).
TEST(InterchangeRecord, GapsModelsAndTheSessionClock) {
  test::TempDir dir;
  db::Database d(dir.File("g.db"));
  const auto se = test::AddStudySession(d,
                                        {.name = "gap study",
                                         .protocol_toml = "# protocol",
                                         .protocol_hash = db::HashText("# protocol")},
                                        "P07")
                      .session;
  // Three main trials; the second has the virtual sample on the left.
  std::vector<db::Trial> planned;
  for (const char* name : {"Cork", "Denim", "Towel"}) {
    const std::string m = name;
    const int k = static_cast<int>(planned.size());
    planned.push_back({.session_id = se,
                       .plan_index = k,
                       .phase = PhaseKind::kMain,
                       .material = m,
                       .comparison = "virtual",
                       .method = "FF",
                       .left = (k == 1 ? "virtual:" : "real:") + m,
                       .right = (k == 1 ? "real:" : "virtual:") + m});
  }
  const auto ids = test::AddTrials(d, planned);
  auto ramp = [](std::size_t n, float base) {
    std::vector<float> v;
    for (std::size_t i = 0; i < n; ++i) v.push_back(base + static_cast<float>(i) * 0.25f);
    return v;
  };
  for (const auto id : ids) {
    d.StartTrial(id);
    // 100 Hz, one channel: left 10 samples, 5 dropped, 5 more; right 10 samples.
    d.InsertTrajectoryChunk({.trial_id = id,
                             .stream = "left_force",
                             .start_time_s = 0,
                             .rate_hz = 100,
                             .channels = {"fz_N"},
                             .samples = ramp(10, 1),
                             .attempt = 1});
    d.InsertTrajectoryChunk({.trial_id = id,
                             .stream = "left_force",
                             .start_time_s = 0.15,
                             .rate_hz = 100,
                             .channels = {"fz_N"},
                             .samples = ramp(5, 9),
                             .attempt = 1});
    d.InsertTrajectoryChunk({.trial_id = id,
                             .stream = "right_force",
                             .start_time_s = 0,
                             .rate_hz = 100,
                             .channels = {"fz_N"},
                             .samples = ramp(10, 20),
                             .attempt = 1});
    d.CompleteTrial(id, {{"roughness", 40.5, 1.5}});
  }
  // A fourth trial that recorded samples and then faulted: not exported.
  const auto faulted = d.AddTrial(
      {.session_id = se, .plan_index = 3, .phase = PhaseKind::kMain, .material = "Acryl"});
  d.StartTrial(faulted);
  d.InsertTrajectoryChunk({.trial_id = faulted,
                           .stream = "left_force",
                           .start_time_s = 0,
                           .rate_hz = 100,
                           .channels = {"fz_N"},
                           .samples = ramp(7, 50),
                           .attempt = 1});
  d.SetTrialStatus(faulted, db::TrialStatus::kFaulted);
  d.SaveMaterialModel("Cork v1", "[material]\nname = \"Cork\"\n");
  // Session at 10:00:00; trials 1 and 2 stamped 0.5 s apart (overlapping their 0.3 s of
  // stimuli + 1.5 s of rating), trial 3 a minute in; an event 2.0 s in.
  d.Exec("UPDATE session SET started_at='2026-01-01T10:00:00.000Z'");
  d.Exec(fmt::format("UPDATE trial SET started_at='2026-01-01T10:00:01.000Z' WHERE id={}", ids[0]));
  d.Exec(fmt::format("UPDATE trial SET started_at='2026-01-01T10:00:01.500Z' WHERE id={}", ids[1]));
  d.Exec(fmt::format("UPDATE trial SET started_at='2026-01-01T10:01:00.123Z' WHERE id={}", ids[2]));
  d.LogEvent({.session_id = se, .kind = db::EventKind::kBreak, .detail = "after trial 2"});
  d.Exec("UPDATE event SET created_at='2026-01-01T10:00:02.000Z' WHERE kind='break'");

  // XDF through libxdf.
  db::ExportXdf(d, dir.File("g.xdf"));
  Xdf x;
  ASSERT_EQ(x.load_xdf(dir.File("g.xdf")), 0);
  ASSERT_EQ(x.streams.size(), 4u);
  std::map<std::string, const Xdf::Stream*> by;
  for (const auto& s : x.streams) by[s.info.name] = &s;
  const auto& left = *by.at("left_force");
  ASSERT_EQ(left.time_stamps.size(), 45u);  // the faulted trial's 7 samples are not there
  // Trial starts: 1.0 (its stamp), 1.0 + 0.3 + 1.5 = 2.8 (its stamp, 1.5, would overlap),
  // 60.123 (to the microsecond: stamps are subtracted as integers).
  const double starts[] = {1.0, 2.8, 60.123};
  for (int k = 0; k < 3; ++k) {
    const std::size_t o = static_cast<std::size_t>(k) * 15;
    EXPECT_NEAR(left.time_stamps[o], starts[k], 1e-9) << k;
    EXPECT_NEAR(left.time_stamps[o + 9], starts[k] + 0.09, 1e-9) << k;
    EXPECT_NEAR(left.time_stamps[o + 10], starts[k] + 0.15, 1e-9) << k;  // after the gap
    EXPECT_EQ(left.time_series[0][o + 10], 9.0f);
    EXPECT_NEAR(by.at("right_force")->time_stamps[static_cast<std::size_t>(k) * 10],
                starts[k] + 0.2, 1e-9)
        << k;
  }
  std::vector<double> trial_marks, rating_marks;
  double break_at = -1;
  for (const auto& [ev, stream] : x.eventMap) {
    const auto j = json::parse(ev.first);
    if (x.streams[static_cast<std::size_t>(stream)].info.name == "ratings")
      rating_marks.push_back(ev.second);
    else if (j["marker"] == "trial_start")
      trial_marks.push_back(ev.second);
    else if (j["kind"] == "break")
      break_at = ev.second;
  }
  ASSERT_EQ(trial_marks.size(), 3u);
  ASSERT_EQ(rating_marks.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(trial_marks[static_cast<std::size_t>(k)], starts[k], 1e-9);
    EXPECT_NEAR(rating_marks[static_cast<std::size_t>(k)], starts[k] + 0.3 + 1.5, 1e-9);
  }
  // The event 0.5 s after trial 2's stamp keeps that offset from trial 2's start.
  EXPECT_NEAR(break_at, 2.8 + 0.5, 1e-9);

  // BIDS: the gap as n/a rows, the stored model with its hash, and the validator's approval.
  ASSERT_TRUE(fs::exists(test::BidsValidator())) << "run scripts/setup";
  const std::string ds = dir.File("bids");
  db::ExportBids(d, ds);
  const auto rows = test::Gunzip(
      ds +
      "/sub-P07/ses-1/beh/sub-P07_ses-1_task-gapstudy_run-1_recording-leftforce_physio.tsv.gz");
  EXPECT_EQ(rows,
            "1\n1.25\n1.5\n1.75\n2\n2.25\n2.5\n2.75\n3\n3.25\nn/a\nn/a\nn/a\nn/a\nn/"
            "a\n9\n9.25\n9.5\n9.75\n10\n");
  const std::string model_hash = db::HashText("[material]\nname = \"Cork\"\n");
  const std::string model_file = ds + "/code/models/Corkv1-" + model_hash.substr(0, 12) + ".toml";
  ASSERT_TRUE(fs::exists(model_file));
  EXPECT_TRUE(fs::exists(
      ds +
      "/sub-P07/ses-1/beh/sub-P07_ses-1_task-gapstudy_run-3_recording-leftforce_physio.tsv.gz"));
  EXPECT_FALSE(fs::exists(
      ds +
      "/sub-P07/ses-1/beh/sub-P07_ses-1_task-gapstudy_run-4_recording-leftforce_physio.tsv.gz"));
  EXPECT_EQ(db::HashText(test::ReadFile(model_file)), model_hash);
  EXPECT_NE(test::ReadFile(ds + "/code/hashes.tsv").find(model_hash), std::string::npos);
  const auto report = test::ValidateBids(ds);
  ASSERT_TRUE(report.contains("issues")) << report.dump(2);
  EXPECT_EQ(report["issues"]["errors"].size(), 0u) << report["issues"]["errors"].dump(2);
}

}  // namespace
}  // namespace hapticlab::db::export_xdf_test
