// Descriptives, outlier fences and correlations against R 4.2.2 (values from the R lines
// quoted beside each case, options(digits = 17)).
#include "hapticlab/stats/descriptive.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "hapticlab/core/status.hpp"

namespace hapticlab::stats::descriptive_test {
namespace {

const std::vector<double> kX = {4.17, 5.58, 5.18, 6.11, 4.50, 4.61, 5.17, 4.53, 5.33, 5.14, 9.80};
const std::vector<double> kY = {4.81, 4.17, 4.41, 3.59, 5.87, 3.83, 6.03, 4.89, 4.32, 4.69, 7.10};

TEST(Descriptive, MatchesRMeanSdSeMedianAndTInterval) {
  const auto d = Describe(kX);
  EXPECT_EQ(d.n, 11);
  EXPECT_NEAR(d.mean, 5.4654545454545458, 1e-13);   // mean(x)
  EXPECT_NEAR(d.sd, 1.5403594621799397, 1e-13);     // sd(x)
  EXPECT_NEAR(d.se, 0.46443585257495446, 1e-13);    // sd(x) / sqrt(11)
  EXPECT_NEAR(d.median, 5.17, 1e-13);               // median(x)
  EXPECT_NEAR(d.ci95_lo, 4.430626978076921, 1e-9);  // t.test(x)$conf.int
  EXPECT_NEAR(d.ci95_hi, 6.5002821128321706, 1e-9);
  EXPECT_THROW(Describe({}), PreconditionError);
}

TEST(Descriptive, QuartileRulesDifferAsRsFivenumAndQuantileDo) {
  // n = 10: Tukey's hinges and R's type-7 quartiles differ.
  const std::vector<double> x = {4.17, 5.58, 5.18, 6.11, 4.50, 4.61, 5.17, 4.53, 5.33, 7.9};
  const auto h = Outliers(x, QuartileRule::kHinges);
  EXPECT_NEAR(h.q1, 4.53, 1e-12);  // fivenum(x)[2]
  EXPECT_NEAR(h.q3, 5.58, 1e-12);  // fivenum(x)[4]
  EXPECT_NEAR(h.upper, 5.58 + 1.5 * (5.58 - 4.53), 1e-12);
  ASSERT_EQ(h.outliers.size(), 1u);
  EXPECT_EQ(h.outliers[0], 9u);  // R's which(): 10 (1-based)
  const auto q = Outliers(x, QuartileRule::kType7);
  EXPECT_NEAR(q.q1, 4.55, 1e-12);    // quantile(x, .25)
  EXPECT_NEAR(q.q3, 5.5175, 1e-12);  // quantile(x, .75)
  ASSERT_EQ(q.outliers.size(), 1u);
  EXPECT_EQ(q.outliers[0], 9u);
}

TEST(Descriptive, PearsonAndSpearmanMatchRsCorTest) {
  const auto p = Pearson(kX, kY);  // cor.test(x, y)
  EXPECT_EQ(p.n, 11);
  EXPECT_NEAR(p.r, 0.53452501795395246, 1e-12);
  EXPECT_NEAR(p.t, 1.8973791895092151, 1e-10);
  EXPECT_NEAR(p.p, 0.090265514420201129, 1e-9);
  const auto s = Spearman(kX, kY);  // cor.test(x, y, method = "spearman", exact = FALSE)
  EXPECT_NEAR(s.r, -0.21818181818181817, 1e-12);
  EXPECT_NEAR(s.p, 0.519248247554982, 1e-9);
  EXPECT_THROW(Pearson({1, 2}, {1, 2}), PreconditionError);
}

}  // namespace
}  // namespace hapticlab::stats::descriptive_test
