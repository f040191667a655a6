// The options and the CSV loading every `stats` subcommand shares
// (apps/hapticlab/cmd_stats_common.cpp), in this process: the parsed options, --where and
// --average-by, the simulated observer's rows left out beside a person's, and bad input as an
// InputError naming file, line and field.

#include "cmd_stats_common.hpp"

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/error_of.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cli::stats_cmd::cmd_stats_common_test {
namespace {

// key column `name` -> row -> response, for a table with unique key combinations.
std::map<std::string, double> ByKey(const stats::LongTable& t, const std::string& name) {
  std::map<std::string, double> out;
  const std::size_t c = t.Key(name);
  for (std::size_t r = 0; r < t.rows(); ++r) out[t.keys[c][r]] = t.y[r];
  return out;
}

TEST(StatsCommon, OptionsParseIntoTheSharedStruct) {
  test::TempDir dir;
  test::WriteFile(dir.File("d.csv"), "subject,score\nS1,1\n");
  CLI::App app;
  Common c;
  AddCommon(&app, c);
  app.parse("--csv " + dir.File("d.csv") +
                " --dv score --where criterion=rough --where phase=main --average-by subject,method"
                " --json --include-simulated",
            false);
  EXPECT_EQ(c.csv, dir.File("d.csv"));
  EXPECT_EQ(c.dv, "score");
  EXPECT_EQ(c.where, (std::vector<std::string>{"criterion=rough", "phase=main"}));
  EXPECT_EQ(c.average_by, "subject,method");
  EXPECT_TRUE(c.json);
  EXPECT_TRUE(c.include_simulated);
  EXPECT_FALSE(c.allow_missing);
  // --dv is required; a --csv that does not exist is refused at parsing.
  CLI::App a2;
  Common c2;
  AddCommon(&a2, c2);
  EXPECT_THROW(a2.parse("--csv " + dir.File("d.csv"), false), CLI::RequiredError);
  CLI::App a3;
  Common c3;
  AddCommon(&a3, c3);
  EXPECT_THROW(a3.parse("--csv " + dir.File("none.csv") + " --dv score", false),
               CLI::ValidationError);
}

TEST(StatsCommon, WhereSelectsRowsAndAverageByTakesCellMeans) {
  test::TempDir dir;
  test::WriteFile(dir.File("d.csv"),
                  "subject,method,criterion,score\n"
                  "S1,A,rough,1\n"
                  "S1,A,rough,3\n"
                  "S1,B,rough,5\n"
                  "S1,A,soft,100\n"
                  "S2,A,rough,7\n");
  Common c{.csv = dir.File("d.csv"), .dv = "score"};
  c.where = {"criterion=rough"};
  c.average_by = "subject,method";
  const auto t = Load(c, {"subject", "method"});
  ASSERT_EQ(t.rows(), 3u);  // (S1, A), (S1, B), (S2, A); the soft row is left out
  std::map<std::string, double> mean;
  const std::size_t s = t.Key("subject"), m = t.Key("method");
  for (std::size_t r = 0; r < t.rows(); ++r) mean[t.keys[s][r] + t.keys[m][r]] = t.y[r];
  EXPECT_DOUBLE_EQ(mean.at("S1A"), 2.0);
  EXPECT_DOUBLE_EQ(mean.at("S1B"), 5.0);
  EXPECT_DOUBLE_EQ(mean.at("S2A"), 7.0);
  // Without --average-by the repetitions stay rows, and the --where column is a key.
  c.average_by.clear();
  const auto raw = Load(c, {"subject", "method"});
  EXPECT_EQ(raw.rows(), 4u);
  EXPECT_EQ(raw.Levels("criterion"), (std::vector<std::string>{"rough"}));
}

TEST(StatsCommon, SimulatedRowsAreLeftOutBesideRatedOnesUnlessAsked) {
  test::TempDir dir;
  test::WriteFile(dir.File("mixed.csv"),
                  "subject,source,score\n"
                  "P01,participant,1\n"
                  "P02,participant,2\n"
                  "SIM,simulated,3\n"
                  "OLD,,4\n");
  Common c{.csv = dir.File("mixed.csv"), .dv = "score"};
  const auto people = ByKey(Load(c, {"subject"}), "subject");
  EXPECT_EQ(people.size(), 3u);  // the row without a source is no simulated one
  EXPECT_EQ(people.count("SIM"), 0u);
  c.include_simulated = true;
  EXPECT_EQ(ByKey(Load(c, {"subject"}), "subject").size(), 4u);
  // A file of the simulated observer alone is analysed as it is.
  test::WriteFile(dir.File("sim.csv"),
                  "subject,source,score\nSIM1,simulated,3\nSIM2,simulated,4\n");
  const Common only{.csv = dir.File("sim.csv"), .dv = "score"};
  EXPECT_EQ(Load(only, {"subject"}).rows(), 2u);
}

TEST(StatsCommon, BadInputNamesFileLineAndField) {
  test::TempDir dir;
  const std::string csv = dir.File("bad.csv");
  test::WriteFile(csv,
                  "subject,criterion,score\n"
                  "S1,rough,1\n"
                  "S2,rough,oops\n");
  Common c{.csv = csv, .dv = "score"};
  EXPECT_EQ(test::WhereOf([&] { Load(c, {"subject"}); }), csv + "|3|score");
  // A --where without '=' (or without a column) is the command line's error.
  c.where = {"criterion"};
  EXPECT_EQ(test::WhereOf([&] { Load(c, {"subject"}); }), std::string(kCommandLine) + "|0|--where");
  c.where = {"=rough"};
  EXPECT_EQ(test::WhereOf([&] { Load(c, {"subject"}); }), std::string(kCommandLine) + "|0|--where");
  // A selection that keeps no row names the file and the option.
  test::WriteFile(csv, "subject,criterion,score\nS1,rough,1\n");
  c.where = {"criterion=soft"};
  EXPECT_EQ(test::WhereOf([&] { Load(c, {"subject"}); }), csv + "|0|--where");
}

}  // namespace
}  // namespace hapticlab::cli::stats_cmd::cmd_stats_common_test
