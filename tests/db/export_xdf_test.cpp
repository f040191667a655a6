// The XDF export (db/src/export_xdf.cpp) read back by libxdf (Debian's libxdf-dev), a reader
// this project did not write: one stream per recorded stream with its channels' units, every
// timestamp on the session clock, trial starts and ratings as markers, and the file-or-folder
// choice of the output.

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
#include "hapticlab/test/test_util.hpp"
#include "interchange_record.hpp"

namespace hapticlab::db {
namespace {

namespace tr = test_record;
using nlohmann::json;

TEST(ExportXdf, StreamsAndMarkersOnTheSessionClock) {
  test::TempDir dir;
  Database d(dir.File("x.db"));
  tr::Fill(d);
  const auto files = ExportXdf(d, dir.File("s.xdf"));
  ASSERT_EQ(files.size(), 1u);
  // 8 + 3 samples of trial A, 4 of B (the faulted trial's 5 are not exported), 3 events
  // (two trial starts and the break), 2 ratings.
  EXPECT_EQ(files[0].rows, 4u + 3u + 4u + 3u + 2u);
  Xdf x;
  ASSERT_EQ(x.load_xdf(dir.File("s.xdf")), 0);
  std::map<std::string, const Xdf::Stream*> by;
  for (const auto& s : x.streams) by[s.info.name] = &s;
  ASSERT_EQ(by.size(), 4u);
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
    if (j["marker"] == "trial_start") start_of[j["plan_index"].get<int>()] = t;
    if (j["marker"] == "event" && j["kind"] == "break") break_at = t;
  }
  EXPECT_NEAR(start_of.at(0), tr::kTrialAStart_s, 1e-9);
  EXPECT_NEAR(start_of.at(1), tr::kTrialBStart_s, 1e-9);
  EXPECT_NEAR(break_at, tr::kEvent_s, 1e-9);
  // Ratings at the stimuli's end + the response time: 1.0 + 0.07 + 0.5, 1.57 + 0.06 + 0.25.
  std::map<int, std::pair<double, double>> rating_of;
  for (const auto& [t, j] : ratings)
    rating_of[j["plan_index"].get<int>()] = {t, j["score"].get<double>()};
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

}  // namespace
}  // namespace hapticlab::db
