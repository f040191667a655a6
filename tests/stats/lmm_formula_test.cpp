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
#include "lmm_reference.hpp"

namespace hapticlab::stats::lmm_formula_test {
namespace {

using nlohmann::json;
constexpr double kRel = 1e-5;

void ExpectClose(double got, const json& want, const std::string& what, double scale = 0) {
  lmm_reference::ExpectClose(got, want, what, scale, kRel);
}

json Ref(const std::string& fit) {
  return lmm_reference::Ref(fit, "stats/lmm_formula_reference.json");
}

LmmResult Fit(const json& ref, bool kenward_roger = false) {
  LmmOptions o;
  o.kenward_roger = kenward_roger;
  return FitLmm(lmm_reference::Load(ref), ref["formula"].get<std::string>(), o);
}

void Compare(const std::string& fit) {
  const json ref = Ref(fit);
  ASSERT_FALSE(ref.is_null()) << fit;
  const json& w = ref["reml"];
  const auto r = Fit(ref);
  const std::string tag = fit + " ";
  EXPECT_TRUE(r.converged) << tag << r.BriefReport();
  ExpectClose(r.deviance, w["REMLcrit"], tag + "REML criterion");
  lmm_reference::ExpectFitMatches(r, w, tag, kRel);
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
}  // namespace hapticlab::stats::lmm_formula_test
