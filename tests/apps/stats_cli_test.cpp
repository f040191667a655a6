// hapticlab stats on the R fixture study: JSON keys and values through the command line.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab {
namespace {

using nlohmann::json;

std::string Cli() { return HL_CLI_PATH; }
std::string Csv() { return test::DataPath("stats/example_raw.csv"); }

json Ref() {
  std::ifstream f(test::DataPath("stats/example_output.json"));
  return json::parse(f)["criteria"]["realism"];
}

json Stats(const std::string& args) {
  std::string out;
  const int rc = test::RunCommand(Cli() + " stats " + args + " --json", &out);
  EXPECT_EQ(rc, 0) << out;
  return json::parse(out);
}

TEST(StatsCli, RmAnovaJson) {
  const auto j = Stats("rm-anova --csv " + Csv() + " --dv score --subject subject --within method,material --where criterion=realism");
  const auto r = Ref()["two_way_rm"];
  ASSERT_EQ(j["effects"].size(), 3u);
  EXPECT_EQ(j["effects"][2]["effect"], "method:material");
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(j["effects"][i]["F"].get<double>(), r["none"][i]["F"].get<double>(), 1e-6 * r["none"][i]["F"].get<double>());
    EXPECT_NEAR(j["effects"][i]["p"].get<double>(), r["none"][i]["p"].get<double>(), 1e-6 * r["none"][i]["p"].get<double>());
  }
  for (const char* key : {"df1", "df2", "pes", "mauchly_W", "mauchly_p", "gg_epsilon", "p_gg", "hf_epsilon", "p_hf"})
    EXPECT_TRUE(j["effects"][0].contains(key)) << key;
  EXPECT_TRUE(j["effects"][2]["mauchly_W"].is_null());  // singular: no test
  EXPECT_NEAR(j["effects"][0]["mauchly_p"].get<double>(), r["mauchly"][0]["p_R"].get<double>(), 1e-8);
}

TEST(StatsCli, TukeyKruskalShapiroJson) {
  const auto t = Stats("tukey --csv " + Csv() + " --dv score --factor method --where criterion=realism --average-by subject,method");
  ASSERT_EQ(t["comparisons"].size(), 3u);
  const auto ref = Ref()["tukey_hsd_between"]["on_subject_means"]["pairs"][0];
  EXPECT_EQ(t["comparisons"][0]["a"].get<std::string>() + "-" + t["comparisons"][0]["b"].get<std::string>(),
            ref["contrast"].get<std::string>());
  EXPECT_NEAR(t["comparisons"][0]["lwr"].get<double>(), ref["lwr"].get<double>(), 1e-6);
  EXPECT_NEAR(t["comparisons"][0]["p_adj"].get<double>(), ref["p_adj"].get<double>(), 1e-9);
  const auto k = Stats("kruskal --csv " + Csv() + " --dv score --group method --where criterion=realism --average-by subject,method,material");
  EXPECT_NEAR(k["H"].get<double>(), Ref()["kruskal_wallis"]["on_cell_means"]["H"].get<double>(), 1e-6);
  EXPECT_EQ(k["dunn"].size(), 3u);
  for (const char* key : {"a", "b", "z", "p", "p_adj"}) EXPECT_TRUE(k["dunn"][0].contains(key)) << key;
  const auto s = Stats("shapiro --csv " + Csv() + " --dv score --where criterion=realism");
  EXPECT_NEAR(s["groups"][0]["W"].get<double>(), Ref()["shapiro"]["all_raw"]["W"].get<double>(), 1e-9);
  EXPECT_EQ(s["groups"][0]["n"], 900);
}

TEST(StatsCli, BadInputExitsWithTwoAndNamesIt) {
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " stats kruskal --csv " + Csv() + " --dv nope --group method", &out), 2);
  EXPECT_NE(out.find("nope"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " stats kruskal --csv " + Csv() + " --dv score --group method --where criterion", &out), 2);
  EXPECT_NE(out.find("--where"), std::string::npos) << out;
  test::TempDir dir;
  test::WriteFile(dir.File("bad.csv"), "subject,cond,score\nS1,a,1\nS1,b,x\n");
  EXPECT_EQ(test::RunCommand(Cli() + " stats shapiro --csv " + dir.File("bad.csv") + " --dv score", &out), 2);
  EXPECT_NE(out.find("bad.csv:3: score"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab
