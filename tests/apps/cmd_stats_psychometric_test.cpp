// hapticlab stats psychometric on psyphy's ecc2 (tests/data/psychometric): every link against
// R's glm (ecc2_links.csv), the stimuli at chosen performances against the closed form of
// psi^-1 with R's coefficients, bad input, the figure and the lean binary.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_stats_psychometric_test {
namespace {

using nlohmann::json;

std::string Cli() { return HL_CLI_PATH; }
std::string Ecc2() { return test::DataPath("psychometric/ecc2.csv"); }
const std::string kEcc2Args =
    " --level Contr --correct Correct --incorrect Incorrect --by task,Size";

json RunJson(const std::string& binary, const std::string& args) {
  std::string out;
  const int rc = test::RunCommand(binary + args + " --json", &out);
  EXPECT_EQ(rc, 0) << out;
  return rc == 0 ? json::parse(out) : json();
}

// The inverse of the standard normal CDF by bisection on erfc (independent of the library's
// EtaOfCore), to 1e-15.
double InverseNormal(double p) {
  double lo = -40, hi = 40;
  for (int i = 0; i < 200; ++i) {
    const double mid = (lo + hi) / 2;
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
  }
  return (lo + hi) / 2;
}

// psi^-1(p) with R's coefficients: F = (p - guess) / (1 - guess), eta = F^-1(F), x from eta.
double ClosedForm(const std::string& link, double a, double b, double p) {
  const bool mafc = link.rfind("mafc-", 0) == 0;
  const double guess = mafc ? 0.25 : 0, F = (p - guess) / (1 - guess);
  if (link.find("logit") != std::string::npos) return (std::log(F / (1 - F)) - a) / b;
  if (link.find("probit") != std::string::npos) return (InverseNormal(F) - a) / b;
  return std::exp((std::log(-std::log(1 - F)) - a) / b);  // weibull: cloglog of ln x
}

TEST(StatsPsychometricCli, EveryLinkEqualsRAndThresholdsTheClosedForm) {
  const CsvTable ref = ReadCsv(test::DataPath("psychometric/ecc2_links.csv"));
  int checked = 0;
  for (const std::string link :
       {"logit", "probit", "weibull", "mafc-logit:4", "mafc-probit:4", "mafc-weibull:4"}) {
    SCOPED_TRACE(link);
    const json j = RunJson(Cli(), " stats psychometric --csv " + Ecc2() + kEcc2Args + " --link " +
                                      link + " --performance 0.6,0.75,0.9 --bootstrap 0");
    ASSERT_EQ(j["groups"].size(), 8u);
    for (const auto& g : j["groups"]) {
      SCOPED_TRACE(g["name"].get<std::string>());
      std::size_t r = 0;
      while (r < ref.rows.size() && !(ref.rows[r][ref.Require("link")] == link &&
                                      ref.rows[r][ref.Require("task")] == g["group"]["task"] &&
                                      ref.Number(r, ref.Require("size")) ==
                                          std::stod(g["group"]["Size"].get<std::string>())))
        ++r;
      ASSERT_LT(r, ref.rows.size());
      const double a = ref.Number(r, ref.Require("a")), b = ref.Number(r, ref.Require("b"));
      const double dev = ref.Number(r, ref.Require("deviance"));
      EXPECT_NEAR(g["a"].get<double>(), a, 1e-6 * std::max(1.0, std::abs(a)));
      EXPECT_NEAR(g["b"].get<double>(), b, 1e-6 * std::max(1.0, std::abs(b)));
      EXPECT_NEAR(g["deviance"].get<double>(), dev, 1e-6 * std::max(1.0, dev));
      EXPECT_EQ(g["df_residual"].get<int>(), ref.Number(r, ref.Require("df_residual")));
      for (const auto& at : g["stimulus_at"]) {
        const double p = at["performance"].get<double>();
        const double x = ClosedForm(link, a, b, p);
        EXPECT_NEAR(at["value"].get<double>(), x, 1e-6 * std::max(1e-3, std::abs(x))) << p;
        // And exactly (to rounding) the closed form of the command's own coefficients.
        const double own = ClosedForm(link, g["a"].get<double>(), g["b"].get<double>(), p);
        EXPECT_NEAR(at["value"].get<double>(), own, 1e-12 * std::abs(own)) << p;
      }
      // The JND is the stimulus at --jnd-at (0.75 by default), the threshold F(alpha) = 0.5
      // (logit, probit) or 1 - 1/e (Weibull).
      EXPECT_NEAR(g["jnd"]["value"].get<double>(), g["stimulus_at"][1]["value"].get<double>(),
                  1e-12);
      const double g0 = link.rfind("mafc-", 0) == 0 ? 0.25 : 0;
      const double f_alpha = link.find("weibull") != std::string::npos ? 1 - std::exp(-1.0) : 0.5;
      const double x_alpha = ClosedForm(link, a, b, g0 + (1 - g0) * f_alpha);
      EXPECT_NEAR(g["threshold"]["value"].get<double>(), x_alpha, 1e-6 * std::abs(x_alpha));
      ++checked;
    }
  }
  EXPECT_EQ(checked, 48);
}

// Intervals from the parametric bootstrap hold the estimate; the Weber fraction is JND /
// reference with its interval scaled alike; the lean binary prints the same JSON.
TEST(StatsPsychometricCli, BootstrapWeberAndTheLeanBinary) {
  const std::string args =
      " --csv " + Ecc2() + kEcc2Args + " --link mafc-logit:4 --bootstrap 200 --reference 0.5";
  const json j = RunJson(Cli(), " stats psychometric" + args + " --seed 7");
  std::string lean;
  ASSERT_EQ(
      test::RunCommand(std::string(HL_STATS_CLI_PATH) + " psychometric" + args + " --seed 7 --json",
                       &lean),
      0)
      << lean;
  EXPECT_EQ(json::parse(lean), j);
  for (const auto& g : j["groups"]) {
    for (const char* key : {"threshold", "slope", "jnd"}) {
      EXPECT_LE(g[key]["lo"].get<double>(), g[key]["value"].get<double>()) << key;
      EXPECT_GE(g[key]["hi"].get<double>(), g[key]["value"].get<double>()) << key;
    }
    EXPECT_DOUBLE_EQ(g["weber_fraction"]["value"].get<double>(),
                     g["jnd"]["value"].get<double>() / 0.5);
    EXPECT_DOUBLE_EQ(g["weber_fraction"]["hi"].get<double>(), g["jnd"]["hi"].get<double>() / 0.5);
    EXPECT_EQ(g["bootstrap_replicates"].get<int>() + g["bootstrap_failed"].get<int>(), 200);
  }
  // A different seed gives different intervals (the bootstrap is not a constant).
  const json k = RunJson(Cli(), " stats psychometric" + args + " --seed 8");
  EXPECT_NE(k["groups"][0]["threshold"]["lo"], j["groups"][0]["threshold"]["lo"]);
}

TEST(StatsPsychometricCli, FigureWrittenByTheFullBinaryRefusedByTheLeanOne) {
  test::TempDir dir;
  const std::string args = " psychometric --csv " + Ecc2() + kEcc2Args +
                           " --link mafc-weibull:4 --bootstrap 0 --figure " + dir.File("fig");
  std::string out;
  ASSERT_EQ(test::RunCommand(Cli() + " stats" + args, &out), 0) << out;
  for (const char* group : {"task_DET__Size_12.4", "task_ID__Size_83"}) {
    const std::string png = dir.File(std::string("fig_") + group + ".png");
    ASSERT_TRUE(std::filesystem::exists(png)) << png << "\n" << out;
    EXPECT_EQ(test::ReadFile(png).substr(1, 3), "PNG");
    EXPECT_TRUE(std::filesystem::exists(dir.File(std::string("fig_") + group + ".svg")));
  }
  EXPECT_EQ(test::RunCommand(std::string(HL_STATS_CLI_PATH) + args, &out), 2) << out;
  EXPECT_NE(out.find("--figure"), std::string::npos) << out;
}

// Bad input: exit 2 with the file, the line and the column (or the option) named.
TEST(StatsPsychometricCli, BadInputExitsTwoNamingFileLineAndColumn) {
  test::TempDir dir;
  const std::string csv = dir.File("bad.csv");
  test::WriteFile(csv, "level,k,n\n0.1,3,10\n0.2,x,10\n");
  std::string out;
  const std::string base = Cli() + " stats psychometric --csv " + csv + " --level level";
  EXPECT_EQ(test::RunCommand(base + " --correct k --trials n", &out), 2);
  EXPECT_NE(out.find(csv + ":3"), std::string::npos) << out;
  EXPECT_NE(out.find("k"), std::string::npos) << out;
  test::WriteFile(csv, "level,k,n\n0.1,3,10\n0.2,12,10\n");
  EXPECT_EQ(test::RunCommand(base + " --correct k --trials n", &out), 2);
  EXPECT_NE(out.find(csv + ":3"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(base + " --correct k --trials missing", &out), 2);
  EXPECT_NE(out.find("missing"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(base + " --correct k", &out), 2);  // neither --trials nor --incorrect
  EXPECT_NE(out.find("--trials"), std::string::npos) << out;
  test::WriteFile(csv, "level,k,n\n0.1,3,10\n0.2,8,10\n");
  EXPECT_EQ(test::RunCommand(base + " --correct k --trials n --link mafc-logit:1", &out), 2);
  EXPECT_NE(out.find("--link"), std::string::npos) << out;
  EXPECT_EQ(test::RunCommand(base + " --correct k --trials n --link mafc-logit:2 "
                                    "--performance 0.4",
                             &out),
            2);
  EXPECT_NE(out.find("--performance"), std::string::npos) << out;
  test::WriteFile(csv, "level,k,n\n0,3,10\n0.2,8,10\n");
  EXPECT_EQ(test::RunCommand(base + " --correct k --trials n --link weibull", &out), 2);
  EXPECT_NE(out.find(csv + ":2"), std::string::npos) << out;
  // Perfectly separated data: no fit exists; said, exit 2.
  test::WriteFile(csv, "level,k,n\n0.1,0,10\n0.2,10,10\n");
  EXPECT_EQ(test::RunCommand(base + " --correct k --trials n", &out), 2);
  EXPECT_NE(out.find("not usable"), std::string::npos) << out;
}

}  // namespace
}  // namespace hapticlab::cmd_stats_psychometric_test
