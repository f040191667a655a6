// The report's inputs (stats/src/report_sources.cpp). The real-time timing sentence from
// stored side_timing rows: the lateness percentiles are those of all ticks of all real-clock
// sides together (the histograms merged), checked against the nearest-rank percentiles of
// the raw values; a study that ran only on a virtual clock says so. The ratings read from a
// database: a study with any person's rating leaves the simulated observer's out (unless
// asked), every kept rating is counted by source, and a score off the protocol's scale is
// refused.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/latency_histogram.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/timing.hpp"
#include "hapticlab/stats/report.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::report_sources_test {
namespace {

struct Fixture {
  test::TempDir dir;
  db::Database d{dir.File("t.db")};
  std::int64_t study = 0, trial = 0;
  Fixture() {
    study = d.CreateStudy({.name = "s", .protocol_toml = "x", .seed = 1});
    const auto p = d.AddParticipant({.study_id = study, .code = "P01"});
    const auto se = d.StartSession({.participant_id = p});
    trial = d.AddTrial({.session_id = se, .phase = PhaseKind::kMain, .material = "m"});
  }
  // A force-loop row of `values` [s] (its percentiles from the histogram, as the engine stores
  // them).
  void Add(const std::string& side, const std::vector<double>& values,
           const std::string& clock = "real") {
    LatencyHistogram h;
    for (const double v : values) h.Add(v);
    const auto s = h.Snapshot();
    db::SideTiming t{.trial_id = trial,
                     .attempt = 1,
                     .side = side,
                     .loop = "force",
                     .clock = clock,
                     .rate_hz = 1000,
                     .achieved_rate_hz = 999.5,
                     .ticks = static_cast<std::int64_t>(values.size())};
    t.late_p50_us = s.Quantile(0.5) * 1e6;
    t.late_max_us = s.max_s * 1e6;
    t.late_histogram = s.Sparse();
    t.priority = "not requested (normal scheduling)";
    t.timer_slack_ns = 1;
    db::SaveSideTiming(d, t);
  }
};

double NearestRank(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1];
}

TEST(TimingReport, PercentilesAreOverAllTicksOfAllSides) {
  Fixture f;
  // Left: 1000 ticks 2-4 us late; right: 1000 ticks 40-60 us late; each value a quarter into
  // a 0.5 us bin, so the histogram's percentile (the bin's upper edge, at most the maximum)
  // is the nearest-rank value plus 0.375 us.
  constexpr double w = LatencySummary::kBinWidthS;
  std::vector<double> left, right, all;
  for (int i = 0; i < 1000; ++i) left.push_back((4 + (i % 5) + 0.25) * w);
  for (int i = 0; i < 1000; ++i) right.push_back((80 + (i % 41) + 0.25) * w);
  f.Add("left", left);
  f.Add("right", right);
  all = left;
  all.insert(all.end(), right.begin(), right.end());
  const std::string s = TimingMethodsSentence(f.d, f.study);
  // The pooled median lies in the left side's values; p99 in the right's.
  const double max_us = (120 + 0.25) * w * 1e6;
  auto edge = [&](double q) { return std::min(NearestRank(all, q) * 1e6 + 0.375, max_us); };
  const std::string expect =
      fmt::format("p50 {:.1f} us, p99 {:.1f} us, p99.9 {:.1f} us (max {:.1f} us)", edge(0.5),
                  edge(0.99), edge(0.999), max_us);
  EXPECT_NE(s.find(expect), std::string::npos) << s << "\nexpected: " << expect;
  EXPECT_NE(s.find("2 trial sides on the real clock"), std::string::npos) << s;
  EXPECT_NE(s.find("over 2000 ticks"), std::string::npos) << s;
  EXPECT_NE(s.find("timer slack 1 ns on 2 of 2 sides"), std::string::npos) << s;
}

TEST(TimingReport, AVirtualClockStudySaysSo) {
  Fixture f;
  f.Add("left", {0, 0, 0}, "virtual");
  EXPECT_NE(TimingMethodsSentence(f.d, f.study).find("virtual clock"), std::string::npos);
  Fixture none;
  EXPECT_NE(TimingMethodsSentence(none.d, none.study).find("No real-time timing"),
            std::string::npos);
}

// A study on the small test protocol (scale 0-100) with one trial of `ratings`.
std::int64_t RatedStudy(db::Database& d, const std::string& name, const std::string& code,
                        const std::vector<db::Rating>& ratings) {
  const auto st = d.CreateStudy(
      {.name = name, .protocol_toml = test::ReadFile(test::DataPath("protocols/small.toml"))});
  const auto p = d.AddParticipant({.study_id = st, .code = code});
  const auto se = d.StartSession({.participant_id = p});
  const auto t = d.AddTrial({.session_id = se,
                             .plan_index = 0,
                             .phase = PhaseKind::kMain,
                             .material = "Cork",
                             .comparison = "virtual",
                             .method = "FF",
                             .repetition = 2});
  d.CompleteTrial(t, ratings);
  return st;
}

TEST(ReportSources, APersonsStudyLeavesTheSimulatedRatingsOut) {
  test::TempDir dir;
  const std::string path = dir.File("r.db");
  {
    db::Database d(path);
    RatedStudy(d, "human", "P01",
               {{"roughness", 70, 1.0, "window"}, {"overall", 20, 1.5, db::kRaterSimulated}});
    RatedStudy(
        d, "sim", "P02",
        {{"roughness", 40, 0.5, db::kRaterSimulated}, {"overall", 45, 0.5, db::kRaterSimulated}});
  }
  RatingSources src;
  const auto t = RatingsFromDatabase(path, false, &src);
  ASSERT_EQ(t.rows(), 3u);
  EXPECT_EQ(t.source, path);
  EXPECT_EQ(src.human.at("human"), 1u);
  EXPECT_EQ(src.simulated_excluded.at("human"), 1u);
  EXPECT_EQ(src.simulated_kept.at("sim"), 2u);  // a simulated study keeps its ratings
  EXPECT_FALSE(src.simulated_kept.contains("human"));
  const auto human = t.Where({{"study", "human"}});
  ASSERT_EQ(human.rows(), 1u);
  EXPECT_EQ(human.y[0], 70);
  EXPECT_EQ(human.keys[human.Key("participant")][0], "P01");
  EXPECT_EQ(human.keys[human.Key("criterion")][0], "roughness");
  EXPECT_EQ(human.keys[human.Key("repetition")][0], "2");
  EXPECT_EQ(human.keys[human.Key("method")][0], "FF");
  // Asked for, the simulated ratings of the person's study are kept too.
  RatingSources all;
  EXPECT_EQ(RatingsFromDatabase(path, true, &all).rows(), 4u);
  EXPECT_EQ(all.simulated_kept.at("human"), 1u);
  EXPECT_TRUE(all.simulated_excluded.empty());
}

TEST(ReportSources, AScoreOffTheProtocolsScaleIsRefused) {
  test::TempDir dir;
  const std::string path = dir.File("r.db");
  {
    db::Database d(path);
    RatedStudy(d, "s", "P01", {{"roughness", 100.5, 1.0, "window"}});
  }
  try {
    RatingsFromDatabase(path);
    ADD_FAILURE() << "a score above the scale was read";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("r.db"), std::string::npos) << what;
    EXPECT_NE(what.find("rating.score"), std::string::npos) << what;
    EXPECT_NE(what.find("100.5"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace hapticlab::stats::report_sources_test
