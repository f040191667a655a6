// Psychometric ML fits against R's glm (binomial family, psyphy links) on psyphy's ecc2
// data set, and the parametric bootstrap's coverage of known parameters.
#include "hapticlab/stats/psychometric.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/stats/psychometric_csv.hpp"
#include "hapticlab/stats/psychometric_report.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::psychometric_test {
namespace {

using psychophysics::Shape;

// Issue #32 asks for agreement to 1e-6. Both sides converge far tighter (glm with
// epsilon = 1e-14; Fisher scoring to 1e-13 in log-likelihood), so this is the only slack.
constexpr double kRTol = 1e-6;

PsychometricData Ecc2(const std::string& task, double size) {
  const CsvTable t = ReadCsv(test::DataPath("psychometric/ecc2.csv"));
  PsychometricData d;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    if (t.rows[r][t.Require("task")] != task || t.Number(r, t.Require("Size")) != size) continue;
    const int c = static_cast<int>(t.Number(r, t.Require("Correct")));
    const int w = static_cast<int>(t.Number(r, t.Require("Incorrect")));
    d.x.push_back(t.Number(r, t.Require("Contr")));
    d.n.push_back(c + w);
    d.k.push_back(c);
  }
  return d;
}

TEST(PsychometricFit, MatchesRGlmOnEcc2) {
  const CsvTable ref = ReadCsv(test::DataPath("psychometric/ecc2_fits.csv"));
  ASSERT_GE(ref.rows.size(), 10u);
  for (std::size_t r = 0; r < ref.rows.size(); ++r) {
    const std::string name = ref.rows[r][ref.Require("name")];
    const double size = ref.Number(r, ref.Require("size"));
    SCOPED_TRACE(name + " size " + std::to_string(size));
    PsychometricFitOptions o;
    o.shape = *psychophysics::ParseShape(ref.rows[r][ref.Require("shape")]);
    o.guess = ref.Number(r, ref.Require("guess"));
    o.lapse_free = ref.rows[r][ref.Require("lapse_mode")] == "free";
    o.lapse = o.lapse_free ? 0 : ref.Number(r, ref.Require("lapse"));
    const PsychometricFit f = FitPsychometric(Ecc2(ref.rows[r][ref.Require("task")], size), o);
    ASSERT_TRUE(f.usable) << f.message;
    auto rel = [](double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(b)); };
    EXPECT_LT(rel(f.params.threshold, ref.Number(r, ref.Require("threshold"))), kRTol)
        << f.params.threshold;
    EXPECT_LT(rel(f.params.slope, ref.Number(r, ref.Require("slope"))), kRTol) << f.params.slope;
    EXPECT_LT(rel(f.a, ref.Number(r, ref.Require("a"))), kRTol);
    EXPECT_LT(rel(f.log_likelihood, ref.Number(r, ref.Require("loglik"))), kRTol)
        << f.log_likelihood;
    EXPECT_NEAR(f.params.lapse, ref.Number(r, ref.Require("lapse")), kRTol);
    // The solver summary: the cost is the negative log-likelihood, and Newton lowered it.
    EXPECT_TRUE(f.converged) << f.BriefReport();
    EXPECT_EQ(f.final_cost, -f.log_likelihood);
    EXPECT_GE(f.initial_cost, f.final_cost) << f.BriefReport();
    EXPECT_GT(f.iterations, 0);
  }
}

TEST(PsychometricFit, RejectsMalformedData) {
  PsychometricFitOptions o;
  EXPECT_THROW(FitPsychometric({{1, 2}, {10}, {5, 5}}, o), PreconditionError);
  const auto k_above_n = FitPsychometric({{1, 2}, {10, 10}, {11, 5}}, o);
  EXPECT_FALSE(k_above_n.usable);
  EXPECT_FALSE(k_above_n.converged);
  EXPECT_EQ(k_above_n.message, "bin 0 has k = 11 of n = 10");
  o.shape = Shape::kWeibull;
  const auto weibull_at_zero = FitPsychometric({{0, 2}, {10, 10}, {5, 5}}, o);
  EXPECT_FALSE(weibull_at_zero.usable);
  EXPECT_EQ(weibull_at_zero.message, "a Weibull needs stimuli > 0");
  o.guess = 1.2;
  EXPECT_THROW(FitPsychometric({{1, 2}, {10, 10}, {5, 5}}, o), PreconditionError);
  // One stimulus value only: no slope can be estimated.
  EXPECT_FALSE(FitPsychometric({{1, 1}, {10, 10}, {5, 6}}, {}).usable);
}

// Simulated 2AFC data from a known Weibull; in at least 90 % of seeds the 95 % bootstrap
// interval holds the true threshold, and separately the true slope (the property).
// 40 seeds x 200 replicates: each interval's coverage is estimated to +-3.5 % (binomial SD
// at 95 %), and the test costs about 1 s in release.
TEST(PsychometricBootstrap, CoversTrueParametersInAtLeast90PercentOfSeeds) {
  const psychophysics::PsychometricParams truth{
      .threshold = 0.2, .slope = 3.0, .guess = 0.5, .lapse = 0.0};
  const std::vector<double> levels{0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4};
  constexpr int kSeeds = 40, kReplicates = 200, kTrialsPerLevel = 40;
  PsychometricFitOptions o;
  o.shape = Shape::kWeibull;
  o.guess = 0.5;
  int thr_in = 0, slope_in = 0, usable = 0;
  std::vector<double> estimates, widths;
  for (int seed = 0; seed < kSeeds; ++seed) {
    Rng rng(DeriveSeed(2024, static_cast<std::uint64_t>(seed)));
    PsychometricData d;
    for (double x : levels) {
      const double p = psychophysics::Psi(Shape::kWeibull, x, truth);
      int k = 0;
      for (int j = 0; j < kTrialsPerLevel; ++j) k += rng.Uniform() < p;
      d.x.push_back(x);
      d.n.push_back(kTrialsPerLevel);
      d.k.push_back(k);
    }
    const auto fit = FitPsychometric(d, o);
    if (!fit.usable) continue;
    ++usable;
    const auto b = BootstrapPsychometric(d, o, fit, kReplicates,
                                         DeriveSeed(77, static_cast<std::uint64_t>(seed)));
    estimates.push_back(fit.params.threshold);
    widths.push_back(b.threshold.hi - b.threshold.lo);
    thr_in += b.threshold.lo <= truth.threshold && truth.threshold <= b.threshold.hi;
    slope_in += b.slope.lo <= truth.slope && truth.slope <= b.slope.hi;
  }
  EXPECT_EQ(usable, kSeeds);
  EXPECT_GE(thr_in, 0.9 * kSeeds) << thr_in << " of " << kSeeds;
  EXPECT_GE(slope_in, 0.9 * kSeeds) << slope_in << " of " << kSeeds;
  // Not covering by being wide: a 95 % interval spans about 3.9 sampling SDs of the estimate;
  // the mean width must lie within [2, 6] SDs (the SD estimated from the 40 fits, +-11 %).
  double mean = 0, var = 0, width = 0;
  for (double e : estimates) mean += e / kSeeds;
  for (double e : estimates) var += (e - mean) * (e - mean) / (kSeeds - 1);
  for (double w : widths) width += w / kSeeds;
  EXPECT_GT(width, 2 * std::sqrt(var));
  EXPECT_LT(width, 6 * std::sqrt(var));
}

TEST(PsychometricFit, RecoversLapseWhenFree) {
  // Many trials from a function with a 4 % lapse: the free fit finds it, a fit with the
  // lapse fixed at 0 has a lower likelihood.
  const psychophysics::PsychometricParams truth{
      .threshold = 1.0, .slope = 4.0, .guess = 1.0 / 3, .lapse = 0.04};
  PsychometricData d;
  for (double x = -0.5; x <= 3.0; x += 0.25) {
    const double p = psychophysics::Psi(Shape::kLogistic, x, truth);
    constexpr int n = 2000;
    d.x.push_back(x);
    d.n.push_back(n);
    d.k.push_back(static_cast<int>(std::lround(p * n)));  // expected counts
  }
  PsychometricFitOptions o{.shape = Shape::kLogistic, .guess = 1.0 / 3, .lapse_free = true};
  const auto f = FitPsychometric(d, o);
  ASSERT_TRUE(f.usable) << f.message;
  EXPECT_NEAR(f.params.lapse, 0.04, 2e-3);  // rounding the counts moves it slightly
  EXPECT_NEAR(f.params.threshold, 1.0, 0.02);
  EXPECT_NEAR(f.params.slope, 4.0, 0.1);
  o.lapse_free = false;
  EXPECT_LT(FitPsychometric(d, o).log_likelihood, f.log_likelihood);
}

// Every link of `stats psychometric --link` on every task x Size group of ecc2, read through
// the command's CSV reader, against R's glm (tests/data/psychometric/ecc2_links.csv):
// coefficients, standard errors, residual deviance and log-likelihood to 1e-6.
TEST(PsychometricFit, EveryLinkMatchesRGlmOnEveryEcc2Group) {
  const CsvTable ref = ReadCsv(test::DataPath("psychometric/ecc2_links.csv"));
  ASSERT_EQ(ref.rows.size(), 48u);  // 8 groups x 6 links
  const auto groups = ReadPsychometricCsv(test::DataPath("psychometric/ecc2.csv"),
                                          {.level = "Contr",
                                           .correct = "Correct",
                                           .trials = "",
                                           .incorrect = "Incorrect",
                                           .by = {"task", "Size"}},
                                          true);
  ASSERT_EQ(groups.size(), 8u);
  auto rel = [](double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(b)); };
  int checked = 0;
  for (std::size_t r = 0; r < ref.rows.size(); ++r) {
    const std::string task = ref.rows[r][ref.Require("task")];
    const double size = ref.Number(r, ref.Require("size"));
    const std::string link_name = ref.rows[r][ref.Require("link")];
    SCOPED_TRACE(task + " " + std::to_string(size) + " " + link_name);
    const PsychometricGroup* g = nullptr;
    for (const auto& x : groups)
      if (x.keys[0].second == task && std::stod(x.keys[1].second) == size) g = &x;
    ASSERT_NE(g, nullptr);
    ASSERT_EQ(g->data.x.size(), 6u);
    std::string why;
    const auto link = ParsePsychometricLink(link_name, &why);
    ASSERT_TRUE(link) << why;
    const auto f = FitPsychometric(g->data, {.shape = link->shape, .guess = link->guess});
    ASSERT_TRUE(f.usable) << f.message;
    EXPECT_LT(rel(f.a, ref.Number(r, ref.Require("a"))), kRTol) << f.a;
    EXPECT_LT(rel(f.b, ref.Number(r, ref.Require("b"))), kRTol) << f.b;
    EXPECT_LT(rel(f.se_a, ref.Number(r, ref.Require("se_a"))), kRTol) << f.se_a;
    EXPECT_LT(rel(f.se_b, ref.Number(r, ref.Require("se_b"))), kRTol) << f.se_b;
    EXPECT_LT(rel(f.deviance, ref.Number(r, ref.Require("deviance"))), kRTol) << f.deviance;
    EXPECT_LT(rel(f.log_likelihood, ref.Number(r, ref.Require("loglik"))), kRTol);
    ++checked;
  }
  EXPECT_EQ(checked, 48);
}

TEST(PsychometricLink, ParsesTheNamedLinksAndRefusesOthers) {
  std::string why;
  const auto m = ParsePsychometricLink("mafc-probit:3", &why);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->shape, Shape::kNormal);
  EXPECT_DOUBLE_EQ(m->guess, 1.0 / 3);
  const auto w = ParsePsychometricLink("weibull", &why);
  ASSERT_TRUE(w);
  EXPECT_EQ(w->shape, Shape::kWeibull);
  EXPECT_EQ(w->guess, 0);
  for (const char* bad :
       {"mafc-logit", "mafc-logit:1", "mafc-logit:x", "logit:2", "cauchit", "mafc-logit:4x", ""}) {
    EXPECT_FALSE(ParsePsychometricLink(bad, &why)) << bad;
    EXPECT_FALSE(why.empty()) << bad;
  }
}

// Bad cells are refused with the file, the line and the column named.
TEST(PsychometricCsv, NamesFileLineAndColumnOfABadCell) {
  test::TempDir dir;
  const PsychometricColumns cols{
      .level = "x", .correct = "k", .trials = "n", .incorrect = "", .by = {}};
  auto error_of = [&](const std::string& body, bool positive = false) -> std::string {
    test::WriteFile(dir.File("d.csv"), "x,k,n\n" + body);
    try {
      ReadPsychometricCsv(dir.File("d.csv"), cols, positive);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string f = dir.File("d.csv");
  EXPECT_NE(error_of("1,2,4\nabc,2,4\n").find(f + ":3"), std::string::npos);
  EXPECT_NE(error_of("1,2,4\nabc,2,4\n").find("x"), std::string::npos);
  EXPECT_NE(error_of("1,5,4\n").find(f + ":2"), std::string::npos) << error_of("1,5,4\n");
  EXPECT_NE(error_of("1,5,4\n").find("k"), std::string::npos);
  EXPECT_NE(error_of("1,2.5,4\n").find("whole number"), std::string::npos);
  EXPECT_NE(error_of("1,-1,4\n").find("whole number"), std::string::npos);
  EXPECT_NE(error_of("1,0,0\n").find("at least 1 trial"), std::string::npos);
  EXPECT_NE(error_of("1,1,1e300\n").find(f + ":2"), std::string::npos);
  EXPECT_NE(error_of("inf,1,2\n").find("finite"), std::string::npos);
  EXPECT_NE(error_of("0,1,2\n", true).find("> 0"), std::string::npos);
  EXPECT_EQ(error_of("1,1,2\n", true), "no error");
}

}  // namespace
}  // namespace hapticlab::stats::psychometric_test
