// The report's assumption check (stats/src/report_checks.cpp): Shapiro-Wilk on the ANOVA's
// residuals, said as advice only where an effect's p is near 0.05.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "../../stats/src/report_internal.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::report_internal::report_checks_test {
namespace {

// 12 subjects x 2 cells whose residuals are strongly skewed (exponential quantiles).
RmAnovaResult Skewed(double p_method) {
  RmAnovaResult a;
  for (int s = 0; s < 12; ++s) {
    a.subjects.push_back("S" + std::to_string(s));
    a.subject_group.push_back(0);
    const double e = -std::log(1.0 - (s + 0.5) / 12.0);
    a.cells.push_back({50 + 10 * e * e, 55 + 10 * e * e});
  }
  a.effects.push_back({.effect = "method",
                       .df1 = 1,
                       .df2 = 11,
                       .F = 5,
                       .p = p_method,
                       .gg_epsilon = 1,
                       .p_gg = p_method,
                       .hf_epsilon = 1,
                       .p_hf = p_method});
  return a;
}

TEST(ReportChecks, NormalityIsAdviceOnlyWhereAConclusionIsAtStake) {
  const auto sw = ShapiroWilk(AnovaResiduals(Skewed(0.5)));
  ASSERT_LT(sw.p, 0.05) << "the fixture must depart from normality";
  test::TempDir dir;
  Writer w(dir.path());
  std::ostringstream near, far;
  ResidualNormality(near, w, "s", Skewed(0.04), Correction::kGG, false, "t");
  ResidualNormality(far, w, "s", Skewed(0.5), Correction::kGG, false, "t");
  EXPECT_NE(near.str().find(fmt::format("W = {:.4f}", sw.W)), std::string::npos) << near.str();
  EXPECT_NE(near.str().find("Advice: the residuals depart from normality and the conclusion on "
                            "method (p = 0.040)"),
            std::string::npos)
      << near.str();
  EXPECT_EQ(far.str().find("Advice"), std::string::npos) << far.str();
  EXPECT_NE(far.str().find("no effect's p lies between 0.01 and 0.1"), std::string::npos)
      << far.str();
  // With figures, a Q-Q plot is written and linked.
  std::ostringstream fig;
  ResidualNormality(fig, w, "s", Skewed(0.5), Correction::kGG, true, "t");
  EXPECT_NE(fig.str().find("![Q-Q plot of the residuals](s_qq.png)"), std::string::npos);
  EXPECT_EQ(w.files().size(), 3u);  // s_qq.svg, s_qq.png, s_qq.pdf
}

}  // namespace
}  // namespace hapticlab::stats::report_internal::report_checks_test
