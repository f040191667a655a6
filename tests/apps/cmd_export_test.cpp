// hapticlab export --format xdf / bids, checked by readers this project did not write:
// libxdf (Debian's libxdf-dev) loads the XDF file, the official bids-validator (npm,
// installed by scripts/setup into tools/bids-validator) checks the BIDS dataset. Both on a
// database the study runner records through the CLI, as the demo does (the small test
// protocol, one simulated participant, every trajectory stream recorded).

#include <gtest/gtest.h>
#include <xdf.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/interchange.hpp"
#include "hapticlab/test/bids.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_export_test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The CLI runs without this test's ASAN_OPTIONS (which only work around libxdf, below).
std::string Cli() { return std::string("env -u ASAN_OPTIONS ") + HL_CLI_PATH; }

// The unit a channel name's suffix states (STYLE.md §4), written out independently of the
// exporter's table.
std::string ExpectedUnit(const std::string& name) {
  for (const auto& [suffix, unit] : std::vector<std::pair<std::string, std::string>>{
           {"_mps2", "m/s^2"}, {"_mps", "m/s"}, {"_N", "N"}, {"_m", "m"}, {"_s", "s"}})
    if (name.ends_with(suffix)) return unit;
  return "n/a";
}

// What the database holds for P01, read through the db API.
struct Expected {
  struct TrialData {
    db::Trial trial;
    std::vector<db::Rating> ratings;
    std::map<std::string, std::vector<db::TrajectoryChunk>> chunks;  // by stream
  };
  std::vector<TrialData> trials;  // completed trials
  std::vector<db::Event> events;
  std::map<std::string, std::size_t> samples;  // per stream
  std::map<std::string, double> rate_hz;
  std::map<std::string, std::vector<std::string>> channels;
  std::size_t ratings = 0;
};

class Interchange : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    db_ = dir_->File("study.db");
    std::string out;
    // The whole small session (26 trials): training, reference and main trials. Real sides
    // record only force (the device measures); vibration streams come from the virtual sides
    // of Hybrid trials, so the session must reach some.
    ASSERT_EQ(test::RunCommand(Cli() + " study run " + test::DataPath("protocols/small.toml") +
                                   " --db " + db_ + " --participant P01 --record all --quiet",
                               &out),
              0)
        << out;
    db::Database d(db_, {.create = false, .read_only = true});
    const auto st = d.Studies().at(0);
    const auto p = *d.FindParticipant(st.id, "P01");
    const auto se = d.Sessions(p.id).at(0);
    exp_ = new Expected;
    for (const auto& t : d.Trials(se.id)) {
      if (t.status != db::TrialStatus::kCompleted) continue;
      Expected::TrialData td{t, d.Ratings(t.id), {}};
      exp_->ratings += td.ratings.size();
      for (auto& c : d.TrajectoryChunks(t.id)) {
        exp_->samples[c.stream] += c.sample_count();
        exp_->rate_hz[c.stream] = c.rate_hz;
        exp_->channels[c.stream] = c.channels;
        td.chunks[c.stream].push_back(std::move(c));
      }
      exp_->trials.push_back(std::move(td));
    }
    exp_->events = d.Events(se.id);
  }
  static void TearDownTestSuite() {
    delete exp_;
    delete dir_;
  }
  static test::TempDir* dir_;
  static std::string db_;
  static Expected* exp_;
};
test::TempDir* Interchange::dir_ = nullptr;
std::string Interchange::db_;
Expected* Interchange::exp_ = nullptr;

// The recorded database has what the exports need (each test runs in its own process and
// records its own: about a second in a release build).
void CheckRecorded(const Expected& e) {
  ASSERT_GE(e.trials.size(), 10u);
  EXPECT_GT(e.ratings, 0u);
  EXPECT_EQ(e.samples.size(), 4u);  // left/right x force/vibration
  for (const auto& [s, n] : e.samples) EXPECT_GT(n, 0u) << s;
}

TEST_F(Interchange, XdfReadBackByLibxdf) {
  CheckRecorded(*exp_);
  const std::string path = dir_->File("P01.xdf");
  std::string out;
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " export --db " + db_ + " --format xdf --participant P01 --out " + path, &out),
      0)
      << out;
  Xdf x;
  ASSERT_EQ(x.load_xdf(path), 0);
  // A stream per recorded stream, plus events and ratings.
  ASSERT_EQ(x.streams.size(), exp_->samples.size() + 2);
  std::map<std::string, int> index;
  for (std::size_t i = 0; i < x.streams.size(); ++i)
    index[x.streams[i].info.name] = static_cast<int>(i);
  ASSERT_TRUE(index.count("events") && index.count("ratings"));

  // Trial starts from the event markers: plan index -> time on the session clock.
  std::map<int, double> trial_start;
  std::size_t logged_events = 0;
  std::map<std::pair<int, std::string>, std::pair<double, double>> rating_marker;  // -> (score, t)
  for (const auto& [ev, stream] : x.eventMap) {
    const auto j = json::parse(ev.first);
    if (stream == index["events"]) {
      if (j["marker"] == "trial_start")
        trial_start[j["trial"].get<int>() - 1] = ev.second;  // plan index
      else
        logged_events += j["marker"] == "event";
    } else {
      ASSERT_EQ(stream, index["ratings"]);
      rating_marker[{j["trial"].get<int>() - 1, j["criterion"].get<std::string>()}] = {
          j["score"].get<double>(), ev.second};
    }
  }
  EXPECT_EQ(trial_start.size(), exp_->trials.size());
  EXPECT_EQ(logged_events, exp_->events.size());
  EXPECT_EQ(rating_marker.size(), exp_->ratings);

  for (const auto& [name, n] : exp_->samples) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(index.count(name));
    const auto& s = x.streams[static_cast<std::size_t>(index[name])];
    EXPECT_EQ(s.info.channel_format, "float32");
    EXPECT_EQ(s.info.nominal_srate, exp_->rate_hz[name]);
    EXPECT_EQ(s.info.sample_count, static_cast<int>(n));  // footer
    ASSERT_EQ(s.time_stamps.size(), n);
    const auto& ch = exp_->channels[name];
    ASSERT_EQ(s.info.channel_count, static_cast<int>(ch.size()));
    ASSERT_EQ(s.info.channels.size(), ch.size());
    ASSERT_EQ(s.time_series.size(), ch.size());
    for (std::size_t c = 0; c < ch.size(); ++c) {
      EXPECT_EQ(s.info.channels[c].at("label"), ch[c]);
      EXPECT_EQ(s.info.channels[c].at("unit"), ExpectedUnit(ch[c]));
    }
    // One clock: no stream runs backwards, so trials do not overlap.
    EXPECT_TRUE(std::is_sorted(s.time_stamps.begin(), s.time_stamps.end()));
  }

  // Values and times per trial, against the database.
  for (const auto& t : exp_->trials) {
    SCOPED_TRACE("plan index " + std::to_string(t.trial.plan_index));
    ASSERT_TRUE(trial_start.count(t.trial.plan_index));
    const double t0 = trial_start[t.trial.plan_index];
    double left_len = 0, right_len = 0;
    for (const auto& [name, chunks] : t.chunks)
      for (const auto& c : chunks) {
        auto& len = name.starts_with("left") ? left_len : right_len;
        len = std::max(len, c.start_time_s + static_cast<double>(c.sample_count()) / c.rate_hz);
      }
    for (const auto& [name, chunks] : t.chunks) {
      const auto& s = x.streams[static_cast<std::size_t>(index[name])];
      // The right stimulus follows the left one.
      const double zero = t0 + (name.starts_with("left") ? 0.0 : left_len);
      for (const auto& c : chunks) {
        const double first = zero + c.start_time_s;
        const auto it = std::lower_bound(s.time_stamps.begin(), s.time_stamps.end(), first - 1e-9);
        ASSERT_NE(it, s.time_stamps.end());
        const auto at = static_cast<std::size_t>(it - s.time_stamps.begin());
        ASSERT_NEAR(*it, first, 1e-9) << name;
        const std::size_t nc = c.channels.size();
        ASSERT_LE(at + c.sample_count(), s.time_stamps.size());
        for (std::size_t i = 0; i < c.sample_count(); ++i) {
          ASSERT_NEAR(s.time_stamps[at + i], first + static_cast<double>(i) / c.rate_hz, 1e-6)
              << name << " " << i;
          for (std::size_t k = 0; k < nc; ++k)
            ASSERT_EQ(s.time_series[k][at + i], c.samples[i * nc + k])
                << name << " sample " << i << " channel " << k;
        }
      }
    }
    for (const auto& r : t.ratings) {
      const auto m = rating_marker.find({t.trial.plan_index, r.criterion});
      ASSERT_NE(m, rating_marker.end()) << r.criterion;
      EXPECT_EQ(m->second.first, r.score);
      EXPECT_NEAR(m->second.second, t0 + left_len + right_len + r.response_time_s, 1e-9);
    }
  }
  // Pseudonymous: no local path in the file.
  EXPECT_EQ(test::ReadFile(path).find(HL_SOURCE_DIR), std::string::npos);
}

TEST_F(Interchange, XdfBadOutputIsRefusedWithTheField) {
  std::string out;
  // Another participant in the same database: a single file cannot hold two sessions.
  const std::string db2 = dir_->File("two.db");
  fs::copy_file(db_, db2);
  ASSERT_EQ(
      test::RunCommand(Cli() + " study run " + test::DataPath("protocols/small.toml") + " --db " +
                           db2 + " --participant P02 --record none --stop-after 1 --quiet",
                       &out),
      3)
      << out;
  EXPECT_EQ(
      test::RunCommand(
          Cli() + " export --db " + db2 + " --format xdf --out " + dir_->File("both.xdf"), &out),
      2);
  EXPECT_NE(out.find("--out"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " export --db " + db2 +
                                 " --format xdf --participant P09 --out " + dir_->File("x.xdf"),
                             &out),
            2);
  EXPECT_NE(out.find("--participant"), std::string::npos) << out;
  // A directory gets one file per session.
  ASSERT_EQ(test::RunCommand(Cli() + " export --db " + db2 + " --format xdf --json --out " +
                                 dir_->File("xdfdir"),
                             &out),
            0)
      << out;
  EXPECT_EQ(json::parse(out)["files"].size(), 2u);
}

TEST_F(Interchange, BidsAcceptedByTheOfficialValidator) {
  // The validator is part of the project's set-up; without it this test fails, never skips.
  ASSERT_TRUE(fs::exists(test::BidsValidator()))
      << test::BidsValidator()
      << " is missing: run scripts/setup (it installs the pinned "
         "bids-validator with npm ci)";
  CheckRecorded(*exp_);
  const std::string ds = dir_->File("bids");
  std::string out;
  ASSERT_EQ(
      test::RunCommand(Cli() + " export --db " + db_ + " --format bids --json --out " + ds, &out),
      0)
      << out;
  const auto report = test::ValidateBids(ds);
  ASSERT_TRUE(report.contains("issues")) << report.dump(2);
  EXPECT_EQ(report["issues"]["errors"].size(), 0u) << report["issues"]["errors"].dump(2);
  for (const auto& w : report["issues"]["warnings"])
    std::cout << "validator warning: " << w["key"] << "\n";
  EXPECT_EQ(report["summary"]["subjects"], json::array({"P01"}));
  EXPECT_EQ(report["summary"]["tasks"], json::array({"test-small"}));

  // Our own look at the contents: one beh row per rating, each physio file as in the db.
  const fs::path beh = fs::path(ds) / "sub-P01" / "ses-1" / "beh";
  const auto tsv = test::ReadFile((beh / "sub-P01_ses-1_task-testsmall_beh.tsv").string());
  EXPECT_EQ(static_cast<std::size_t>(std::count(tsv.begin(), tsv.end(), '\n')), exp_->ratings + 1);
  std::size_t physio = 0;
  for (const auto& t : exp_->trials)
    for (const auto& [name, chunks] : t.chunks) {
      std::string label;
      for (char c : name)
        if (std::isalnum(static_cast<unsigned char>(c))) label += c;
      const std::string stem = "sub-P01_ses-1_task-testsmall_run-" +
                               std::to_string(t.trial.plan_index + 1) + "_recording-" + label +
                               "_physio";
      const auto side = json::parse(test::ReadFile((beh / (stem + ".json")).string()));
      EXPECT_EQ(side["SamplingFrequency"].get<double>(), chunks.front().rate_hz);
      EXPECT_EQ(side["Columns"].get<std::vector<std::string>>(), chunks.front().channels);
      for (const auto& c : chunks.front().channels)
        EXPECT_EQ(side[c]["Units"], ExpectedUnit(c)) << c;
      std::istringstream rows(test::Gunzip((beh / (stem + ".tsv.gz")).string()));
      std::string line;
      std::size_t n = 0;
      for (const auto& c : chunks)
        for (std::size_t i = 0; i < c.sample_count(); ++i, ++n) {
          ASSERT_TRUE(std::getline(rows, line)) << stem;
          std::istringstream cells(line);
          for (std::size_t k = 0; k < c.channels.size(); ++k) {
            std::string cell;
            std::getline(cells, cell, '\t');
            ASSERT_EQ(std::strtof(cell.c_str(), nullptr), c.samples[i * c.channels.size() + k])
                << stem << " row " << n;
          }
        }
      EXPECT_FALSE(std::getline(rows, line)) << stem << ": more rows than samples";
      ++physio;
    }
  EXPECT_GT(physio, 0u);
  // Protocol with its recorded hash; no local paths anywhere.
  const auto hashes = test::ReadFile(ds + "/code/hashes.tsv");
  const auto protocol = test::ReadFile(ds + "/code/protocol-testsmall.toml");
  EXPECT_NE(hashes.find(db::HashText(protocol)), std::string::npos);
  for (const auto& e : fs::recursive_directory_iterator(ds)) {
    if (e.is_regular_file() && !e.path().string().ends_with(".gz")) {
      EXPECT_EQ(test::ReadFile(e.path().string()).find(HL_SOURCE_DIR), std::string::npos)
          << e.path();
    }
  }

  // The validator does look at our physio sidecars: without SamplingFrequency it reports an error.
  const fs::path first = beh / ("sub-P01_ses-1_task-testsmall_run-" +
                                std::to_string(exp_->trials.back().trial.plan_index + 1) +
                                "_recording-leftforce_physio.json");
  auto j = json::parse(test::ReadFile(first.string()));
  j.erase("SamplingFrequency");
  test::WriteFile(first.string(), j.dump());
  const auto broken = test::ValidateBids(ds);
  ASSERT_TRUE(broken.contains("issues")) << broken.dump(2);
  EXPECT_GT(broken["issues"]["errors"].size(), 0u);
}

// Quiet exports (issue #32): one progress line per participant on stderr and one summary on
// stdout, never a line per file; CSV trajectories only on request, their size said first;
// XDF counted in streams and samples.
TEST_F(Interchange, ExportsPrintOneLinePerParticipantAndASummary) {
  std::size_t samples = 0;
  for (const auto& [stream, n] : exp_->samples) samples += n;
  auto lines = [](const std::string& text) {
    std::vector<std::string> v;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) v.push_back(l);
    return v;
  };
  auto has_trajectories = [](const std::string& dir) {
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().filename().string().rfind("trajectory_", 0) == 0) return true;
    return false;
  };
  std::string out;
  const std::string csv = dir_->File("quiet_csv");
  ASSERT_EQ(test::RunCommand(Cli() + " export --db " + db_ + " --out " + csv, &out), 0) << out;
  auto l = lines(out);
  ASSERT_EQ(l.size(), 2u) << out;
  EXPECT_NE(l[0].find("trajectories left out (" + std::to_string(samples) + " samples"),
            std::string::npos)
      << out;
  EXPECT_NE(l[0].find("--trajectories"), std::string::npos) << out;
  EXPECT_NE(l[1].find("3 tables"), std::string::npos) << out;
  EXPECT_FALSE(has_trajectories(csv));

  const std::string full = dir_->File("full_csv");
  ASSERT_EQ(
      test::RunCommand(Cli() + " export --db " + db_ + " --out " + full + " --trajectories", &out),
      0)
      << out;
  l = lines(out);
  ASSERT_EQ(l.size(), 3u) << out;  // the size, P01's line, the summary
  EXPECT_NE(l[0].find("writing trajectories: " + std::to_string(samples) + " samples"),
            std::string::npos)
      << out;
  EXPECT_NE(l[1].find("P01"), std::string::npos) << out;
  EXPECT_NE(l[1].find(std::to_string(samples) + " trajectory samples"), std::string::npos) << out;
  EXPECT_TRUE(has_trajectories(full));
  ASSERT_EQ(test::RunCommand(
                Cli() + " export --db " + db_ + " --out " + full + " --trajectories --quiet", &out),
            0);
  EXPECT_EQ(lines(out).size(), 1u) << out;

  ASSERT_EQ(
      test::RunCommand(
          Cli() + " export --db " + db_ + " --format bids --out " + dir_->File("quiet_bids"), &out),
      0)
      << out;
  l = lines(out);
  ASSERT_EQ(l.size(), 2u) << out;
  EXPECT_EQ(l[0].rfind("sub-P01 (P01): ", 0), 0u) << out;
  EXPECT_NE(l[1].find(std::to_string(samples) + " samples"), std::string::npos) << out;
  EXPECT_EQ(out.find("rows)"), std::string::npos) << out;

  ASSERT_EQ(
      test::RunCommand(
          Cli() + " export --db " + db_ + " --format xdf --out " + dir_->File("quiet_xdf"), &out),
      0)
      << out;
  EXPECT_NE(out.find(std::to_string(exp_->samples.size() + 2) + " streams"), std::string::npos)
      << out;
  EXPECT_EQ(out.find("rows"), std::string::npos) << out;
  ASSERT_EQ(test::RunCommand(Cli() + " export --db " + db_ + " --format xdf --json --out " +
                                 dir_->File("quiet_xdf2"),
                             &out),
            0)
      << out;
  const auto j = json::parse(out)["files"][0];
  EXPECT_EQ(j["streams"], exp_->samples.size() + 2) << out;
  EXPECT_FALSE(j.contains("rows")) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_export_test
