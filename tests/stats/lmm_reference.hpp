// The lme4 / lmerTest reference values (tests/data/stats/lmm_reference.json,
// lmm_formula_reference.json) and their comparison, shared by lmm_test.cpp,
// lmm_formula_test.cpp and lmm_kr_test.cpp.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "hapticlab/stats/lmm.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::lmm_reference {

using nlohmann::json;
inline constexpr double kRel = 1e-4;

inline json Ref(const std::string& design, const std::string& file = "stats/lmm_reference.json") {
  std::ifstream f(test::DataPath(file));
  return json::parse(f)[design];
}

// Relative agreement `rel`, with an absolute floor `scale` * rel for values near zero.
inline void ExpectClose(double got, const json& want, const std::string& what, double scale = 0,
                        double rel = kRel) {
  ASSERT_FALSE(want.is_null()) << what;
  const double w = want.get<double>();
  EXPECT_NEAR(got, w, rel * std::max(std::abs(w), scale)) << what;
}

// A fit against lme4/lmerTest's record `w` (one "reml" or "ml" object of the JSON): σ, logLik,
// θ, the coefficients (estimate, SE, df, t, p), the type 3 F tests and the variance
// components, each to `rel` relative. lme4's as.data.frame(VarCorr) rows are, per term, the
// variances then the correlations (lower triangle, column-major), and last the residual.
inline void ExpectFitMatches(const LmmResult& r, const json& w, const std::string& tag,
                             double rel) {
  const auto close = [rel](double got, const json& want, const std::string& what,
                           double scale = 0) { ExpectClose(got, want, what, scale, rel); };
  EXPECT_EQ(r.singular, w["singular"].get<bool>()) << tag;
  close(r.sigma, w["sigma"], tag + "sigma");
  close(r.logLik, w["logLik"], tag + "logLik");
  ASSERT_EQ(r.theta.size(), w["theta"].size()) << tag;
  for (std::size_t i = 0; i < r.theta.size(); ++i)
    close(r.theta[i], w["theta"][i], tag + "theta", 1.0);
  ASSERT_EQ(r.fixed.size(), w["fixed"].size()) << tag;
  for (std::size_t i = 0; i < r.fixed.size(); ++i) {
    const auto& c = r.fixed[i];
    const auto& e = w["fixed"][i];
    const std::string name = tag + e["name"].get<std::string>();
    EXPECT_EQ(c.name, e["name"].get<std::string>()) << tag;
    // Estimates near zero: compared on the scale of their standard error.
    close(c.estimate, e["estimate"], name + " estimate", e["se"].get<double>());
    close(c.se, e["se"], name + " se");
    close(c.df, e["df"], name + " df");
    close(c.t, e["t"], name + " t", 1.0);
    close(c.p, e["p"], name + " p");
  }
  ASSERT_EQ(r.anova.size(), w["anova"].size()) << tag;
  for (std::size_t i = 0; i < r.anova.size(); ++i) {
    const auto& t = r.anova[i];
    const auto& e = w["anova"][i];
    const std::string name = tag + e["term"].get<std::string>();
    EXPECT_EQ(t.term, e["term"].get<std::string>()) << tag;
    EXPECT_EQ(t.num_df, e["num_df"].get<double>()) << name;
    close(t.den_df, e["den_df"], name + " den df");
    close(t.F, e["F"], name + " F");
    close(t.p, e["p"], name + " p");
  }
  std::size_t row = 0;
  for (const auto& term : r.random) {
    const auto k = term.names.size();
    for (std::size_t i = 0; i < k; ++i, ++row) {
      ASSERT_LT(row, w["random"].size()) << tag;
      const auto& e = w["random"][row];
      EXPECT_EQ(term.group, e["group"].get<std::string>()) << tag;
      EXPECT_EQ(term.names[i], e["var1"].get<std::string>()) << tag;
      close(term.variance[i], e["vcov"], tag + term.group + " var " + term.names[i],
            r.sigma * r.sigma);
      close(term.sd[i], e["sdcor"], tag + term.group + " sd " + term.names[i], r.sigma);
    }
    for (std::size_t j = 0; j < k; ++j)
      for (std::size_t i = j + 1; i < k; ++i, ++row) {
        ASSERT_LT(row, w["random"].size()) << tag;
        const auto& e = w["random"][row];
        EXPECT_EQ(term.names[i], e["var2"].get<std::string>()) << tag;
        close(term.corr[i][j], e["sdcor"],
              tag + term.group + " corr " + term.names[i] + "," + term.names[j], 1.0);
      }
  }
  ASSERT_EQ(row + 1, w["random"].size()) << tag;
  EXPECT_EQ(w["random"][row]["group"].get<std::string>(), "Residual") << tag;
  close(r.sigma, w["random"][row]["sdcor"], tag + "residual sd");
}

inline LongTable Load(const json& ref) {
  const auto f = ParseLmmFormula(ref["formula"].get<std::string>());
  auto cols = f.Columns();
  cols.erase(cols.begin());
  return ReadLongCsv(test::DataPath("stats/" + ref["csv"].get<std::string>()), f.response, cols);
}

}  // namespace hapticlab::stats::lmm_reference
