#include "hapticlab/db/export.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/export_formats.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::export_test {
namespace {

TEST(Export, TablesRoundTripThroughCsv) {
  test::TempDir dir;
  Database db(dir.File("e.db"));
  const auto se =
      test::AddStudySession(db, {.name = "ch5, hybrid", .protocol_toml = "x", .seed = 3}, "P02")
          .session;
  // Plan indices 4 and 7 (plan numbers 5 and 8), unlike the rows' ids 1 and 2.
  const auto ids = test::AddTrials(db, {{.session_id = se,
                                         .plan_index = 4,
                                         .phase = PhaseKind::kMain,
                                         .material = "Denim",
                                         .comparison = "virtual",
                                         .method = "hybrid",
                                         .left = "real",
                                         .right = "virtual"},
                                        {.session_id = se,
                                         .plan_index = 7,
                                         .phase = PhaseKind::kReference,
                                         .material = "Cork",
                                         .comparison = "Velvet"}});
  db.CompleteTrial(ids[0], {{"roughness", 71.25, 1.125}, {"overall", 0.1, 3.0}});
  db.LogEvent({.session_id = se,
               .trial_id = ids[1],
               .kind = db::EventKind::kBreak,
               .detail = "after \"block\" 1"});
  std::vector<float> samples;
  for (int i = 0; i < 30; ++i) samples.push_back(std::sin(0.1f * static_cast<float>(i)) * 1e-3f);
  db.InsertTrajectoryChunk({.trial_id = ids[0],
                            .stream = "force",
                            .start_time_s = 0.5,
                            .rate_hz = 1000,
                            .channels = {"x_m", "y_m", "fz_N"},
                            .samples = samples});

  const auto files = ExportCsv(db, dir.File("out"));
  ASSERT_EQ(files.size(), 4u);

  const auto ratings = ReadCsv(dir.File("out/ratings.csv"));
  ASSERT_EQ(ratings.rows.size(), 2u);
  EXPECT_EQ(ratings.rows[0][ratings.Require("study")], "ch5, hybrid");
  EXPECT_EQ(ratings.rows[0][ratings.Require("participant")], "P02");
  EXPECT_EQ(ratings.rows[0][ratings.Require("method")], "hybrid");
  // Trials by their plan number (plan index + 1), never the database id.
  EXPECT_EQ(ratings.rows[0][ratings.Require("trial")], "5");
  EXPECT_FALSE(ratings.Find("trial_id"));
  std::map<std::string, double> score;
  for (std::size_t r = 0; r < ratings.rows.size(); ++r)
    score[ratings.rows[r][ratings.Require("criterion")]] =
        ratings.Number(r, ratings.Require("score"));
  EXPECT_EQ(score["roughness"], 71.25);
  EXPECT_EQ(score["overall"], 0.1);  // exact: 17 significant digits

  const auto trials = ReadCsv(dir.File("out/trials.csv"));
  ASSERT_EQ(trials.rows.size(), 2u);
  EXPECT_EQ(trials.rows[0][trials.Require("status")], "completed");
  EXPECT_EQ(trials.rows[1][trials.Require("comparison")], "Velvet");
  EXPECT_EQ(trials.rows[1][trials.Require("trial")], "8");

  const auto events = ReadCsv(dir.File("out/events.csv"));
  ASSERT_EQ(events.rows.size(), 1u);
  EXPECT_EQ(events.rows[0][events.Require("detail")], "after \"block\" 1");
  EXPECT_EQ(events.rows[0][events.Require("trial")], "8");

  const auto traj = ReadCsv(dir.File("out/trajectory_force.csv"));
  ASSERT_EQ(traj.rows.size(), 10u);
  EXPECT_EQ(traj.rows[0][traj.Require("trial")], "5");
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_NEAR(traj.Number(i, traj.Require("t_s")), 0.5 + 0.001 * static_cast<double>(i), 1e-12);
    EXPECT_EQ(static_cast<float>(traj.Number(i, traj.Require("x_m"))), samples[i * 3]);
    EXPECT_EQ(static_cast<float>(traj.Number(i, traj.Require("fz_N"))), samples[i * 3 + 2]);
  }
}

TEST(Export, OnlyTheCompletingAttemptIsWrittenAndDamagedChunksAreRefused) {
  test::TempDir dir;
  Database db(dir.File("e.db"));
  const auto se =
      test::AddStudySession(db, {.name = "s", .protocol_toml = "x", .seed = 3}, "P02").session;
  const auto ids = test::AddTrials(
      db, {{.session_id = se, .plan_index = 0, .phase = PhaseKind::kMain, .material = "Denim"},
           {.session_id = se, .plan_index = 1, .phase = PhaseKind::kMain, .material = "Cork"}});
  db.StartTrial(ids[0]);  // attempt 1: interrupted after one chunk
  db.InsertTrajectoryChunk({.trial_id = ids[0],
                            .stream = "force",
                            .rate_hz = 1000,
                            .channels = {"fz_N"},
                            .samples = {7, 7, 7},
                            .attempt = 1});
  db.StartTrial(ids[0]);  // attempt 2 completes
  db.InsertTrajectoryChunk({.trial_id = ids[0],
                            .stream = "force",
                            .rate_hz = 1000,
                            .channels = {"fz_N"},
                            .samples = {1, 2},
                            .attempt = 2});
  db.CompleteTrial(ids[0], {{"overall", 50, 1}},
                   {{.trial_id = ids[0],
                     .attempt = 2,
                     .stream = "force",
                     .rate_hz = 1000,
                     .samples_offered = 2,
                     .samples_written = 2}});
  db.StartTrial(ids[1]);  // started, never completed: not exported
  db.InsertTrajectoryChunk({.trial_id = ids[1],
                            .stream = "force",
                            .rate_hz = 1000,
                            .channels = {"fz_N"},
                            .samples = {9},
                            .attempt = 1});
  ExportCsv(db, dir.File("out"));
  const auto traj = ReadCsv(dir.File("out/trajectory_force.csv"));
  ASSERT_EQ(traj.rows.size(), 2u);
  EXPECT_EQ(traj.Number(0, traj.Require("fz_N")), 1);
  EXPECT_EQ(traj.Number(1, traj.Require("fz_N")), 2);
  // A blob shorter than its row's sample count is damage: refused, never read past its end.
  db.Exec("UPDATE trajectory_chunk SET samples = x'0000' WHERE attempt = 2");
  try {
    ExportCsv(db, dir.File("out2"));
    ADD_FAILURE() << "a damaged chunk was exported";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("e.db"), std::string::npos) << e.what();
  }
}

// The export registry: the built-in formats by name, and a format registered here (one
// function, one registration line) is found and exports through the same entry the CLI uses.
TEST(ExportFormats, BuiltInsAndAToyFormatRegisteredInTheTest) {
  std::vector<std::string> names;
  for (const auto& f : ExportFormats()) names.push_back(f.name);
  ASSERT_GE(names.size(), 3u);
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 3),
            (std::vector<std::string>{"csv", "bids", "xdf"}));
  EXPECT_TRUE(FindExportFormat("xdf")->selects_participants);
  EXPECT_EQ(FindExportFormat("xdf")->file_extension, ".xdf");
  EXPECT_TRUE(FindExportFormat("csv")->chooses_trajectories);
  EXPECT_EQ(FindExportFormat("toy"), nullptr);

  // The toy format: one line per participant of every study.
  RegisterExportFormat({.name = "toy",
                        .help = "participant codes, one per line",
                        .write =
                            [](const Database& db, const ExportRequest& r) {
                              std::string text;
                              std::size_t rows = 0;
                              for (const auto& st : db.Studies())
                                for (const auto& p : db.Participants(st.id))
                                  text += st.name + "," + p.code + "\n", ++rows;
                              test::WriteFile(r.out + "/codes.txt", text);
                              return std::vector<ExportedFile>{{r.out + "/codes.txt", rows}};
                            },
                        .describe =
                            [](const std::vector<ExportedFile>& f) {
                              return std::to_string(f.at(0).rows) + " codes";
                            }});
  EXPECT_THROW(RegisterExportFormat({.name = "toy"}), std::logic_error);
  const ExportFormat* toy = FindExportFormat("toy");
  ASSERT_NE(toy, nullptr);
  EXPECT_EQ(ExportFormats().back().name, "toy");

  test::TempDir dir;
  Database db(dir.File("t.db"));
  const auto st = db.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1});
  db.AddParticipant({.study_id = st, .code = "P01"});
  db.AddParticipant({.study_id = st, .code = "P02"});
  const auto files = toy->write(db, {.out = dir.path()});
  EXPECT_EQ(toy->describe(files), "2 codes");
  EXPECT_EQ(test::ReadFile(dir.File("codes.txt")), "s,P01\ns,P02\n");
}

// The CSV format through the registry writes what ExportCsv writes, and says what it left out.
TEST(ExportFormats, CsvThroughTheRegistryReportsLeftOutTrajectories) {
  test::TempDir dir;
  Database db(dir.File("c.db"));
  const auto se = test::AddStudySession(db).session;
  const auto ids =
      test::AddTrials(db, {{.session_id = se, .plan_index = 0, .phase = PhaseKind::kMain}});
  db.InsertTrajectoryChunk({.trial_id = ids[0],
                            .stream = "force",
                            .start_time_s = 0,
                            .rate_hz = 1000,
                            .channels = {"x_m"},
                            .samples = {1, 2, 3}});
  db.CompleteTrial(ids[0], {{"roughness", 50, 1}});
  std::vector<std::string> lines;
  const auto files = FindExportFormat("csv")->write(
      db, {.out = dir.File("out"), .progress = [&](const std::string& l) { lines.push_back(l); }});
  EXPECT_EQ(files.size(), 3u);  // ratings, trials, events: trajectories left out
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines[0].find("trajectories left out (3 samples of 1 streams"), std::string::npos)
      << lines[0];
  EXPECT_EQ(FindExportFormat("csv")->describe(files).find("3 tables"), 0u);
}

}  // namespace
}  // namespace hapticlab::db::export_test
