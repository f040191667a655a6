// hapticlab stats lmm (apps/hapticlab/cmd_stats_lmm.cpp) through the command line: the JSON
// against lmerTest and the exit code and message on a bad formula.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_stats_lmm_test {
namespace {

using nlohmann::json;

std::string Cli() { return HL_CLI_PATH; }

// hapticlab-stats lmm against lmerTest (tests/data/stats/lmm_reference.R): ML fit, JSON keys.
TEST(StatsCli, LmmJsonAgreesWithLmerTest) {
  std::ifstream f(test::DataPath("stats/lmm_reference.json"));
  const json ref = json::parse(f)["unbalanced"];
  std::string out;
  ASSERT_EQ(test::RunCommand(std::string(HL_STATS_CLI_PATH) + " lmm --csv " +
                                 test::DataPath("stats/lmm_unbalanced.csv") + " --formula '" +
                                 ref["formula"].get<std::string>() + "' --ml --json",
                             &out),
            0)
      << out;
  const json j = json::parse(out);
  EXPECT_EQ(j["method"], "ML");
  const auto& w = ref["ml"];
  ASSERT_EQ(j["anova_type3"].size(), w["anova"].size());
  for (std::size_t i = 0; i < w["anova"].size(); ++i) {
    for (const char* k : {"den_df", "F", "p"})
      EXPECT_NEAR(j["anova_type3"][i][k].get<double>(), w["anova"][i][k].get<double>(),
                  1e-4 * w["anova"][i][k].get<double>())
          << i << " " << k;
  }
  EXPECT_NEAR(j["deviance"].get<double>(), w["deviance"].get<double>(),
              1e-4 * w["deviance"].get<double>());
  for (const char* key :
       {"fixed", "random", "sigma", "logLik", "AIC", "BIC", "theta", "convergence"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_FALSE(j["convergence"]["singular"].get<bool>());
  EXPECT_TRUE(j["convergence"]["converged"].get<bool>());
}

TEST(StatsCli, LmmBadFormulaExitsWithTwoAndNamesFileAndField) {
  const std::string csv = test::DataPath("stats/lmm_singular.csv");
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " stats lmm --csv " + csv +
                                 " --formula 'score ~ methd + (1 | participant)'",
                             &out),
            2);
  EXPECT_NE(out.find("lmm_singular.csv"), std::string::npos) << out;
  EXPECT_NE(out.find("methd"), std::string::npos) << out;
  EXPECT_EQ(
      test::RunCommand(Cli() + " stats lmm --csv " + csv + " --formula 'score ~ method'", &out), 2);
  EXPECT_NE(out.find("--formula"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(
                Cli() + " stats lmm --csv " + csv +
                    " --formula 'score ~ method + (1 | participant)' --ddf kenward-roger --ml",
                &out),
            2);
  EXPECT_NE(out.find("--ddf"), std::string::npos) << out;  // Kenward-Roger needs REML, as lmerTest
}

// lme4's formula language through the CLI: uncorrelated terms and a function of the response
// fit (exit 0, R's names in the JSON); a function outside its domain is exit 2 naming the file
// and the expression.
TEST(StatsCli, LmmFormulaLanguage) {
  const std::string csv = test::DataPath("stats/lmm_sleepstudy.csv");
  std::string out;
  ASSERT_EQ(test::RunCommand(std::string(HL_STATS_CLI_PATH) + " lmm --csv " + csv +
                                 " --formula 'log(Reaction) ~ 0 + I(Days^2) + (Days || Subject)'"
                                 " --json",
                             &out),
            0)
      << out;
  const auto j = nlohmann::json::parse(out);
  ASSERT_EQ(j["fixed"].size(), 1u) << out;
  EXPECT_EQ(j["fixed"][0]["name"].get<std::string>(), "I(Days^2)");
  EXPECT_EQ(j["random"].size(), 2u) << out;  // (1 | Subject) and (0 + Days | Subject)
  EXPECT_EQ(test::RunCommand(Cli() + " stats lmm --csv " + csv +
                                 " --formula 'Reaction ~ log(Days) + (1 | Subject)'",
                             &out),
            2);
  EXPECT_NE(out.find("lmm_sleepstudy.csv"), std::string::npos) << out;
  EXPECT_NE(out.find("log(Days)"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_stats_lmm_test
