// hapticlab stats on the R fixture study: JSON keys and values through the command line.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_stats_test {
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
  const auto j =
      Stats("rm-anova --csv " + Csv() +
            " --dv score --subject subject --within method,material --where criterion=realism");
  const auto r = Ref()["two_way_rm"];
  ASSERT_EQ(j["effects"].size(), 3u);
  EXPECT_EQ(j["effects"][2]["effect"], "method:material");
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(j["effects"][i]["F"].get<double>(), r["none"][i]["F"].get<double>(),
                1e-6 * r["none"][i]["F"].get<double>());
    EXPECT_NEAR(j["effects"][i]["p"].get<double>(), r["none"][i]["p"].get<double>(),
                1e-6 * r["none"][i]["p"].get<double>());
  }
  for (const char* key :
       {"df1", "df2", "pes", "mauchly_W", "mauchly_p", "gg_epsilon", "p_gg", "hf_epsilon", "p_hf"})
    EXPECT_TRUE(j["effects"][0].contains(key)) << key;
  EXPECT_TRUE(j["effects"][2]["mauchly_W"].is_null());  // singular: no test
  EXPECT_NEAR(j["effects"][0]["mauchly_p"].get<double>(), r["mauchly"][0]["p_R"].get<double>(),
              1e-8);
}

TEST(StatsCli, TukeyKruskalShapiroJson) {
  const auto t =
      Stats("tukey --csv " + Csv() +
            " --dv score --factor method --where criterion=realism --average-by subject,method");
  ASSERT_EQ(t["comparisons"].size(), 3u);
  const auto ref = Ref()["tukey_hsd_between"]["on_subject_means"]["pairs"][0];
  EXPECT_EQ(t["comparisons"][0]["a"].get<std::string>() + "-" +
                t["comparisons"][0]["b"].get<std::string>(),
            ref["contrast"].get<std::string>());
  EXPECT_NEAR(t["comparisons"][0]["lwr"].get<double>(), ref["lwr"].get<double>(), 1e-6);
  EXPECT_NEAR(t["comparisons"][0]["p_adj"].get<double>(), ref["p_adj"].get<double>(), 1e-9);
  const auto k = Stats(
      "kruskal --csv " + Csv() +
      " --dv score --group method --where criterion=realism --average-by subject,method,material");
  EXPECT_NEAR(k["H"].get<double>(), Ref()["kruskal_wallis"]["on_cell_means"]["H"].get<double>(),
              1e-6);
  EXPECT_EQ(k["dunn"].size(), 3u);
  for (const char* key : {"a", "b", "z", "p", "p_adj"})
    EXPECT_TRUE(k["dunn"][0].contains(key)) << key;
  const auto s = Stats("shapiro --csv " + Csv() + " --dv score --where criterion=realism");
  EXPECT_NEAR(s["groups"][0]["W"].get<double>(), Ref()["shapiro"]["all_raw"]["W"].get<double>(),
              1e-9);
  EXPECT_EQ(s["groups"][0]["n"], 900);
}

TEST(StatsCli, BadInputExitsWithTwoAndNamesIt) {
  std::string out;
  EXPECT_EQ(
      test::RunCommand(Cli() + " stats kruskal --csv " + Csv() + " --dv nope --group method", &out),
      2);
  EXPECT_NE(out.find("nope"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(Cli() + " stats kruskal --csv " + Csv() +
                                 " --dv score --group method --where criterion",
                             &out),
            2);
  EXPECT_NE(out.find("--where"), std::string::npos) << out;
  test::TempDir dir;
  test::WriteFile(dir.File("bad.csv"), "subject,cond,score\nS1,a,1\nS1,b,x\n");
  EXPECT_EQ(
      test::RunCommand(Cli() + " stats shapiro --csv " + dir.File("bad.csv") + " --dv score", &out),
      2);
  EXPECT_NE(out.find("bad.csv:3: score"), std::string::npos) << out;
}

std::string Mixed() { return test::DataPath("stats/mixed_2x3.csv"); }

json MixedRef() {
  std::ifstream f(test::DataPath("stats/mixed_anova.json"));
  return json::parse(f)["a"];
}

TEST(StatsCli, MixedAnovaWithBetweenAgreesWithAfexAndNamesTheDroppedSubject) {
  const auto j = Stats("rm-anova --csv " + Mixed() +
                       " --dv score --subject subject --within method --between group");
  const auto ref = MixedRef()["anova"];
  ASSERT_EQ(j["effects"].size(), ref.size());
  for (std::size_t i = 0; i < ref.size(); ++i) {
    EXPECT_EQ(j["effects"][i]["effect"], ref[i]["effect"]);
    EXPECT_NEAR(j["effects"][i]["F"].get<double>(), ref[i]["F"].get<double>(),
                1e-10 * ref[i]["F"].get<double>());
  }
  EXPECT_TRUE(j["effects"][0]["between_only"].get<bool>());
  EXPECT_EQ(j["dropped"][0]["subject"], "S17");
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " stats rm-anova --csv " + Mixed() +
                                 " --dv score --subject subject --within method --between group",
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("dropped S17: no rating for method=visual"), std::string::npos) << out;
  // Tukey on the within factor names the dropped subject in its text output too.
  ASSERT_EQ(test::RunCommand(Cli() + " stats tukey --csv " + Mixed() +
                                 " --dv score --subject subject --factor method",
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("dropped S17: no rating for method=visual"), std::string::npos) << out;
  // Tukey on the between factor of the mixed design (emmeans: expert - novice).
  const auto t =
      Stats("tukey --csv " + Mixed() +
            " --dv score --subject subject --within method --between group --factor group");
  ASSERT_EQ(t["comparisons"].size(), 1u);
  const auto tr = MixedRef()["tukey_group"][0];
  EXPECT_EQ(t["comparisons"][0]["a"], "novice");  // a - b = novice - expert = -(expert - novice)
  EXPECT_NEAR(t["comparisons"][0]["diff"].get<double>(), -tr["estimate"].get<double>(), 1e-10);
  EXPECT_NEAR(t["comparisons"][0]["se"].get<double>(), tr["SE"].get<double>(), 1e-10);
}

TEST(StatsCli, ABetweenFactorGivenAsWithinExitsWithTwoAndSaysSo) {
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " stats rm-anova --csv " + Mixed() +
                                 " --dv score --subject subject --within group,method",
                             &out),
            2);
  EXPECT_NE(out.find("'group' is a between-subjects factor"), std::string::npos) << out;
  EXPECT_NE(out.find("give it as a between factor"), std::string::npos) << out;
}

TEST(StatsCli, MissingScoresAreAnErrorOrDropTheirSubjectByName) {
  test::TempDir dir;
  test::WriteFile(
      dir.File("na.csv"),
      "subject,cond,score\nS1,a,1\nS1,b,3\nS2,a,2\nS2,b,NA\nS3,a,4\nS3,b,7\nS4,a,1\nS4,b,2\n");
  std::string out;
  const std::string cmd = Cli() + " stats rm-anova --csv " + dir.File("na.csv") +
                          " --dv score --subject subject --within cond";
  EXPECT_EQ(test::RunCommand(cmd, &out), 2);
  EXPECT_NE(out.find("na.csv:5: score"), std::string::npos) << out;
  ASSERT_EQ(test::RunCommand(cmd + " --missing drop-subject", &out), 0) << out;
  EXPECT_NE(out.find("dropped S2: missing score at " + dir.File("na.csv") + ":5"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("3 subjects"), std::string::npos) << out;
}

// The lean binary runs the same commands with the same output, and its start-up loads none of
// the heavy libraries of the full CLI.
TEST(StatsCli, LeanBinaryGivesTheSameAnswersWithoutTheHeavyLibraries) {
  const std::string args = " rm-anova --csv " + Mixed() +
                           " --dv score --subject subject --within method --between group --json";
  std::string full, lean;
  ASSERT_EQ(test::RunCommand(Cli() + " stats" + args, &full), 0) << full;
  ASSERT_EQ(test::RunCommand(std::string(HL_STATS_CLI_PATH) + args, &lean), 0) << lean;
  EXPECT_EQ(full, lean);
  std::string needed;
  ASSERT_EQ(
      test::RunCommand("readelf -d " + std::string(HL_STATS_CLI_PATH) + " | grep NEEDED", &needed),
      0)
      << needed;
  for (const char* lib : {"opencv", "ceres", "portaudio", "glfw", "plplot", "sqlite", "GL", "usb",
                          "hidapi", "fftw", "ssl", "crypto"})
    EXPECT_EQ(needed.find(lib), std::string::npos) << lib << " in\n" << needed;
  std::string heavy;
  ASSERT_EQ(test::RunCommand("readelf -d " + Cli() + " | grep NEEDED", &heavy), 0);
  EXPECT_NE(heavy.find("opencv"), std::string::npos)
      << "the check above would not notice: " << heavy;
}

// The analysis report names a participant the rmANOVA dropped, with the cells it lacks.
TEST(StatsCli, ReportNamesADroppedParticipant) {
  test::TempDir dir;
  const std::string db = dir.File("s.db"), proto = test::DataPath("protocols/small.toml");
  std::string out;
  for (const char* p : {"P01", "P02"})
    ASSERT_EQ(test::RunCommand(Cli() + " study run " + proto + " --db " + db + " --participant " +
                                   p + " --quiet",
                               &out),
              0)
        << out;
  ASSERT_EQ(test::RunCommand(Cli() + " study run " + proto + " --db " + db +
                                 " --participant P03 --quiet --stop-after 15",
                             &out),
            3)
      << out;
  ASSERT_EQ(test::RunCommand(
                Cli() + " analyze --db " + db + " --out " + dir.File("rep") + " --json", &out),
            0)
      << out;
  const auto md = test::ReadFile(json::parse(out)["report"].get<std::string>());
  const auto at = md.find("- dropped P03: no rating for ");
  ASSERT_NE(at, std::string::npos) << md;
  EXPECT_NE(md.find("1 dropped for missing cells"), std::string::npos) << md;
}

// The analysis report fits the protocol's [analysis] lmm_formula per criterion.
TEST(StatsCli, ReportFitsTheProtocolsLmm) {
  test::TempDir dir;
  const std::string db = dir.File("s.db"), proto = dir.File("small.toml");
  test::WriteFile(dir.File("profiles.toml"),
                  test::ReadFile(test::DataPath("protocols/profiles.toml")));
  test::WriteFile(proto,
                  test::ReadFile(test::DataPath("protocols/small.toml")) +
                      "\n[analysis]\ntests = [\"lmm\"]\n"
                      "lmm_formula = \"score ~ method + (1 | participant) + (1 | material)\"\n");
  std::string out;
  for (const char* p : {"P01", "P02"})
    ASSERT_EQ(test::RunCommand(Cli() + " study run " + proto + " --db " + db + " --participant " +
                                   p + " --quiet",
                               &out),
              0)
        << out;
  ASSERT_EQ(test::RunCommand(
                Cli() + " analyze --db " + db + " --out " + dir.File("rep") + " --json", &out),
            0)
      << out;
  const auto md = test::ReadFile(json::parse(out)["report"].get<std::string>());
  EXPECT_NE(md.find("Linear mixed model `score ~ method + (1 | participant) + (1 | material)`"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| method"), std::string::npos) << md;
  EXPECT_NE(md.find("| participant (Intercept) |"), std::string::npos) << md;
  EXPECT_EQ(md.find("Not fitted"), std::string::npos) << md;
  EXPECT_TRUE(std::ifstream(dir.File("rep/test-small_roughness_lmm.csv")).good());
}

TEST(StatsCli, BetweenEffectsCarryNoSphericityFieldsAndPUsedFollowsTheCorrection) {
  for (const std::string correction : {"GG", "HF", "none"}) {
    const auto j = Stats("rm-anova --csv " + Mixed() +
                         " --dv score --subject subject --within method --between group "
                         "--correction " +
                         correction);
    EXPECT_EQ(j["correction"], correction);
    for (const auto& e : j["effects"]) {
      const double p_used = e["p_used"].get<double>();
      if (e["between_only"].get<bool>()) {
        for (const char* key : {"gg_epsilon", "p_gg", "hf_epsilon", "p_hf", "mauchly_W"})
          EXPECT_FALSE(e.contains(key)) << e["effect"] << " " << key;
        EXPECT_EQ(p_used, e["p"].get<double>());
      } else {
        const char* key = correction == "GG" ? "p_gg" : correction == "HF" ? "p_hf" : "p";
        EXPECT_EQ(p_used, e[key].get<double>()) << e["effect"];
      }
    }
    // The residuals' normality is reported beside the table.
    EXPECT_EQ(j["residual_normality"]["test"], "Shapiro-Wilk");
  }
}

// Every number in a command's JSON is finite; the only nulls are statistics that do not
// exist by design (the residuals' test where it cannot run, a correlation matrix's cells).
void ExpectFiniteJson(const json& j, const std::string& path, const std::string& what) {
  if (j.is_object()) {
    for (const auto& [k, v] : j.items()) ExpectFiniteJson(v, path + "/" + k, what);
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) ExpectFiniteJson(j[i], path, what);
  } else if (j.is_null()) {
    EXPECT_TRUE(path.ends_with("/residual_normality") || path.find("/corr") != std::string::npos)
        << what << ": null at " << path;
  } else if (j.is_number()) {
    EXPECT_TRUE(std::isfinite(j.get<double>())) << what << ": " << path;
  }
}

// Fuzz of the stats readers with extreme values: one score replaced, or every score scaled
// into the far tails of double precision. Each command either answers with finite numbers
// (exit 0) or refuses naming the column and the file (exit 2); never exit 1, never library
// text.
TEST(StatsCli, ExtremeValuesGiveFiniteResultsOrANamedRefusal) {
  test::TempDir dir;
  std::vector<std::array<std::string, 3>> base;  // subject, cond, score
  for (int s = 0; s < 6; ++s)
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 2; ++r)
        base.push_back({"S" + std::to_string(s), "c" + std::to_string(c),
                        std::to_string(40 + 3 * c + ((s * 7 + c * 3 + r * 5) % 11))});
  const auto write = [&](const std::string& name, const std::function<std::string(int)>& score) {
    std::string text = "subject,cond,score\n";
    for (std::size_t i = 0; i < base.size(); ++i)
      text += base[i][0] + "," + base[i][1] + "," + score(static_cast<int>(i)) + "\n";
    test::WriteFile(dir.File(name), text);
    return dir.File(name);
  };
  std::vector<std::string> files;
  for (const std::string v : {"1e300", "-1e300", "1e100", "-1e100", "1e-300", "4.9e-324",
                              "2.225e-309", "1.7976931348623157e308"})
    files.push_back(write("one" + std::to_string(files.size()) + ".csv", [&](int i) {
      return i == 7 ? v : base[static_cast<std::size_t>(i)][2];
    }));
  for (const std::string scale : {"e-300", "e-310", "e300", "e150"})
    files.push_back(write("all" + std::to_string(files.size()) + ".csv",
                          [&](int i) { return base[static_cast<std::size_t>(i)][2] + scale; }));
  const std::vector<std::string> commands{"rm-anova --dv score --subject subject --within cond",
                                          "tukey --dv score --subject subject --factor cond",
                                          "tukey --dv score --factor cond",
                                          "kruskal --dv score --group cond",
                                          "shapiro --dv score --by cond",
                                          "lmm --formula 'score ~ cond + (1 | subject)'"};
  int refused = 0, answered = 0;
  for (const std::string& binary : {Cli() + " stats", std::string(HL_STATS_CLI_PATH)})
    for (const auto& f : files)
      for (const auto& cmd : commands) {
        const std::string what = binary + " " + cmd + " on " + f;
        std::string out;
        const int rc = test::RunCommand(binary + " " + cmd + " --csv " + f + " --json 2>&1", &out);
        EXPECT_TRUE(rc == 0 || rc == 2) << what << " exit " << rc << ": " << out;
        EXPECT_EQ(out.find("boost"), std::string::npos) << what << ": " << out;
        EXPECT_EQ(out.find("Error in function"), std::string::npos) << what << ": " << out;
        if (rc == 0) {
          ++answered;
          ExpectFiniteJson(json::parse(out.substr(out.find('{'))), "", what);
        } else if (rc == 2) {
          ++refused;
          EXPECT_NE(out.find(f), std::string::npos) << what << ": the file is named: " << out;
          EXPECT_NE(out.find("score"), std::string::npos) << what << ": the column: " << out;
        }
      }
  // Both outcomes occur: rank-based tests answer, sums of squares of 1e300 are refused.
  EXPECT_GT(answered, 0);
  EXPECT_GT(refused, 0);
}

}  // namespace
}  // namespace hapticlab::cmd_stats_test
