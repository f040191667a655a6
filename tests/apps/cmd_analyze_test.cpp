// hapticlab analyze through the command line (apps/hapticlab/cmd_analyze.cpp). The report's
// aggregate table is checked against cell means computed here from the study's own export;
// the ANOVA and Tukey numbers are the stats module's (tested against R in tests/stats).
// (The report's sections and figures: StudyCli.RunStopResumeStatusAnalyzeExport; damaged
// databases: FaultCli.AnalyzeAndExportRefuseDamagedRecordsAndBadScores.)

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <tuple>
#include <vector>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_analyze_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }
std::string Small() { return test::DataPath("protocols/small.toml"); }

TEST(AnalyzeCli, AggregateTableIsTheCellMeansOfTheExportedRatings) {
  test::TempDir dir;
  const std::string db = dir.File("s.db");
  std::string out;
  for (const char* p : {"P01", "P02"})
    ASSERT_EQ(test::RunCommand(Cli() + " study run " + Small() + " --db " + db + " --participant " +
                                   p + " --quiet --record none",
                               &out),
              0)
        << out;
  ASSERT_EQ(test::RunCommand(Cli() + " analyze --db " + db + " --out " + dir.File("rep") +
                                 " --no-figures --json",
                             &out),
            0)
      << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j["studies"], nlohmann::json::array({"test-small"}));
  for (const auto& f : j["files"]) {
    const std::string p = f;
    EXPECT_TRUE(std::filesystem::exists(p)) << p;
    EXPECT_FALSE(p.ends_with(".png") || p.ends_with(".svg") || p.ends_with(".pdf"))
        << "--no-figures drew " << p;
  }
  ASSERT_EQ(
      test::RunCommand(
          Cli() + " export --db " + db + " --out " + dir.File("x") + " --no-trajectories", &out),
      0)
      << out;
  // From the export: main-phase scores per (criterion, material, method), and the real-real
  // upper limit per criterion (reference trials comparing a material with itself).
  const auto ratings = ReadCsv(dir.File("x/ratings.csv"));
  const auto phase = ratings.Require("phase"), crit = ratings.Require("criterion"),
             mat = ratings.Require("material"), cmp = ratings.Require("comparison"),
             meth = ratings.Require("method"), score = ratings.Require("score");
  std::map<std::tuple<std::string, std::string, std::string>, std::vector<double>> cells;
  std::map<std::string, std::pair<double, int>> upper;
  for (std::size_t i = 0; i < ratings.rows.size(); ++i) {
    const auto& r = ratings.rows[i];
    if (r[phase] == "main") cells[{r[crit], r[mat], r[meth]}].push_back(ratings.Number(i, score));
    if (r[phase] == "reference" && r[mat] == r[cmp]) {
      upper[r[crit]].first += ratings.Number(i, score);
      ++upper[r[crit]].second;
    }
  }
  ASSERT_EQ(cells.size(), 2u * 4u * 2u);  // criteria x materials x methods
  const auto agg = ReadCsv(dir.File("rep/test-small_aggregate.csv"));
  ASSERT_EQ(agg.rows.size(), cells.size());
  for (std::size_t i = 0; i < agg.rows.size(); ++i) {
    const auto& r = agg.rows[i];
    const auto key = std::make_tuple(r[agg.Require("criterion")], r[agg.Require("material")],
                                     r[agg.Require("method")]);
    ASSERT_EQ(cells.count(key), 1u) << r[0] << " " << r[2] << " " << r[3];
    const auto& v = cells[key];
    double mean = 0, ss = 0;
    for (double x : v) mean += x / static_cast<double>(v.size());
    for (double x : v) ss += (x - mean) * (x - mean);
    const double sd = std::sqrt(ss / static_cast<double>(v.size() - 1));
    EXPECT_EQ(agg.Number(i, agg.Require("n")), static_cast<double>(v.size()));
    EXPECT_NEAR(agg.Number(i, agg.Require("mean")), mean, 1e-5);  // written with 6 decimals
    EXPECT_NEAR(agg.Number(i, agg.Require("sd")), sd, 1e-5);
    const auto& u = upper.at(std::get<0>(key));
    ASSERT_GT(u.second, 0);
    EXPECT_NEAR(agg.Number(i, agg.Require("ratio_to_upper")), mean / (u.first / u.second), 1e-5);
  }
}

TEST(AnalyzeCli, AMissingDatabaseIsBadInputNamingItAndTheOption) {
  test::TempDir dir;
  std::string out;
  EXPECT_EQ(test::RunCommand(
                Cli() + " analyze --db " + dir.File("none.db") + " --out " + dir.File("r"), &out),
            2);
  EXPECT_NE(out.find(dir.File("none.db") + ": --db: no such database file"), std::string::npos)
      << out;
  EXPECT_FALSE(std::filesystem::exists(dir.File("none.db")));
}

}  // namespace
}  // namespace hapticlab::cmd_analyze_test
