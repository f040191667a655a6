// lme4's formula language (issue #32 item 4) against lme4 1.1.31 / lmerTest 3.1.3 on data sets
// that ship with lme4 (sleepstudy, Pastes, cake, Penicillin): tests/data/stats/
// lmm_formula_reference.json, made by lmm_formula_reference.R beside it. Each feature - ||,
// nesting a/b, interaction grouping a:b, functions of the response and of predictors, I()
// arithmetic, 0 + and - 1, poly - is one REML fit; fixed effects, SE, Satterthwaite df, t, θ,
// type 3 F tests, variance components, σ and logLik agree to 1e-5 relative.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/lmm.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats {
namespace {

using nlohmann::json;
constexpr double kRel = 1e-5;

// Relative agreement, with an absolute floor `scale` * kRel for values near zero.
void ExpectClose(double got, const json& want, const std::string& what, double scale = 0) {
  ASSERT_FALSE(want.is_null()) << what;
  const double w = want.get<double>();
  EXPECT_NEAR(got, w, kRel * std::max(std::abs(w), scale)) << what;
}

json Ref(const std::string& fit) {
  std::ifstream f(test::DataPath("stats/lmm_formula_reference.json"));
  return json::parse(f)[fit];
}

LmmResult Fit(const json& ref, bool kenward_roger = false) {
  const auto formula = ref["formula"].get<std::string>();
  const auto f = ParseLmmFormula(formula);
  auto cols = f.Columns();
  cols.erase(cols.begin());
  const auto data =
      ReadLongCsv(test::DataPath("stats/" + ref["csv"].get<std::string>()), f.response, cols);
  LmmOptions o;
  o.kenward_roger = kenward_roger;
  return FitLmm(data, formula, o);
}

void Compare(const std::string& fit) {
  const json ref = Ref(fit);
  ASSERT_FALSE(ref.is_null()) << fit;
  const json& w = ref["reml"];
  const auto r = Fit(ref);
  const std::string tag = fit + " ";
  EXPECT_TRUE(r.converged) << tag << r.BriefReport();
  EXPECT_EQ(r.singular, w["singular"].get<bool>()) << tag;
  ExpectClose(r.sigma, w["sigma"], tag + "sigma");
  ExpectClose(r.logLik, w["logLik"], tag + "logLik");
  ExpectClose(r.deviance, w["REMLcrit"], tag + "REML criterion");
  ASSERT_EQ(r.theta.size(), w["theta"].size()) << tag;
  for (std::size_t i = 0; i < r.theta.size(); ++i)
    ExpectClose(r.theta[i], w["theta"][i], tag + "theta", 1.0);
  ASSERT_EQ(r.fixed.size(), w["fixed"].size()) << tag;
  for (std::size_t i = 0; i < r.fixed.size(); ++i) {
    const auto& c = r.fixed[i];
    const auto& e = w["fixed"][i];
    const std::string name = tag + e["name"].get<std::string>();
    EXPECT_EQ(c.name, e["name"].get<std::string>()) << tag;
    ExpectClose(c.estimate, e["estimate"], name + " estimate", e["se"].get<double>());
    ExpectClose(c.se, e["se"], name + " se");
    ExpectClose(c.df, e["df"], name + " df");
    ExpectClose(c.t, e["t"], name + " t", 1.0);
  }
  ASSERT_EQ(r.anova.size(), w["anova"].size()) << tag;
  for (std::size_t i = 0; i < r.anova.size(); ++i) {
    const auto& t = r.anova[i];
    const auto& e = w["anova"][i];
    const std::string name = tag + e["term"].get<std::string>();
    EXPECT_EQ(t.term, e["term"].get<std::string>()) << tag;
    EXPECT_EQ(t.num_df, e["num_df"].get<double>()) << name;
    ExpectClose(t.den_df, e["den_df"], name + " den df");
    ExpectClose(t.F, e["F"], name + " F");
  }
  // as.data.frame(VarCorr): per term the variances, then the correlations; last the residual.
  std::size_t row = 0;
  for (const auto& term : r.random) {
    const auto k = term.names.size();
    for (std::size_t i = 0; i < k; ++i, ++row) {
      ASSERT_LT(row, w["random"].size()) << tag;
      const auto& e = w["random"][row];
      EXPECT_EQ(term.group, e["group"].get<std::string>()) << tag;
      EXPECT_EQ(term.names[i], e["var1"].get<std::string>()) << tag;
      ExpectClose(term.variance[i], e["vcov"], tag + term.group + " var " + term.names[i],
                  r.sigma * r.sigma);
      ExpectClose(term.sd[i], e["sdcor"], tag + term.group + " sd " + term.names[i], r.sigma);
    }
    for (std::size_t j = 0; j < k; ++j)
      for (std::size_t i = j + 1; i < k; ++i, ++row) {
        ASSERT_LT(row, w["random"].size()) << tag;
        ExpectClose(term.corr[i][j], w["random"][row]["sdcor"], tag + term.group + " corr", 1.0);
      }
  }
  ASSERT_EQ(row + 1, w["random"].size()) << tag;
  EXPECT_EQ(w["random"][row]["group"].get<std::string>(), "Residual") << tag;
}

// Kenward-Roger (pbkrtest's adjusted SEs and df) on the same fits: every random-effects
// structure above (uncorrelated terms of one grouping factor, nested, interaction grouping).
void CompareKenwardRoger(const std::string& fit) {
  const json ref = Ref(fit);
  const json& w = ref["reml"]["kr"];
  const auto r = Fit(ref, true);
  ASSERT_EQ(r.fixed.size(), w.size()) << fit;
  for (std::size_t i = 0; i < r.fixed.size(); ++i) {
    const std::string name = fit + " KR " + w[i]["name"].get<std::string>();
    ExpectClose(r.fixed[i].se, w[i]["se"], name + " se");
    ExpectClose(r.fixed[i].df, w[i]["df"], name + " df");
  }
}

TEST(LmmFormula, KenwardRogerOnEveryStructure) {
  for (const char* fit : {"uncorrelated", "uncorrelated_two", "nested", "interaction_group",
                          "log_response", "functions", "log_crossed", "i_arithmetic",
                          "no_intercept", "minus_one", "poly", "poly_interaction"})
    CompareKenwardRoger(fit);
}

TEST(LmmFormula, UncorrelatedSlopeSleepstudy) { Compare("uncorrelated"); }
TEST(LmmFormula, UncorrelatedThreeTermsSleepstudy) { Compare("uncorrelated_two"); }
TEST(LmmFormula, NestedGroupingPastes) { Compare("nested"); }
TEST(LmmFormula, InteractionGroupingCake) { Compare("interaction_group"); }
TEST(LmmFormula, LogResponseAndPolynomialSleepstudy) { Compare("log_response"); }
TEST(LmmFormula, SqrtScaleExpSleepstudy) { Compare("functions"); }
TEST(LmmFormula, LogResponseCrossedPenicillin) { Compare("log_crossed"); }
TEST(LmmFormula, ArithmeticInsideISleepstudy) { Compare("i_arithmetic"); }
TEST(LmmFormula, NoInterceptCake) { Compare("no_intercept"); }
TEST(LmmFormula, MinusOneSleepstudy) { Compare("minus_one"); }
TEST(LmmFormula, OrthogonalPolynomialSleepstudy) { Compare("poly"); }
TEST(LmmFormula, FactorByPolynomialCake) { Compare("poly_interaction"); }

// A function of a factor, or a value out of a function's domain, is refused naming the column.
TEST(LmmFormula, RefusalsNameTheColumn) {
  const auto path = test::DataPath("stats/lmm_sleepstudy.csv");
  const auto data = ReadLongCsv(path, "Reaction", {"Subject", "Days"});
  auto message = [&](const std::string& formula) {
    try {
      FitLmm(data, formula);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("Reaction ~ log(Subject) + (1 | Subject)").find("Subject"), std::string::npos);
  EXPECT_NE(message("Reaction ~ log(Days) + (1 | Subject)").find("log(Days)"), std::string::npos);
  EXPECT_NE(message("Reaction ~ I(1/Days) + (1 | Subject)").find("row 1"), std::string::npos);
  EXPECT_NE(message("log(Reaction - 300) ~ Days + (1 | Subject)").find("log(Reaction - 300)"),
            std::string::npos);
}

}  // namespace
}  // namespace hapticlab::stats
