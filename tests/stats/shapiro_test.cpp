// Shapiro-Wilk (Royston's AS R94) against R 4.2.2's shapiro.test, options(digits = 17).
#include "hapticlab/stats/shapiro.hpp"

#include <gtest/gtest.h>

#include <boost/math/distributions/normal.hpp>
#include <vector>

namespace hapticlab::stats::shapiro_test {
namespace {

TEST(Shapiro, MatchesRsShapiroTest) {
  const std::vector<double> skewed = {4.17, 5.58, 5.18, 6.11, 4.50, 4.61,
                                      5.17, 4.53, 5.33, 5.14, 9.80};
  const auto a = ShapiroWilk(skewed);
  EXPECT_EQ(a.n, 11);
  EXPECT_NEAR(a.W, 0.68446335443869732, 1e-9);
  EXPECT_NEAR(a.p, 0.00029563960072873823, 1e-9);
  const auto b = ShapiroWilk({4.81, 4.17, 4.41, 3.59, 5.87, 3.83, 6.03, 4.89, 4.32, 4.69, 7.10});
  EXPECT_NEAR(b.W, 0.91795238776313315, 1e-9);
  EXPECT_NEAR(b.p, 0.30195319536366216, 1e-8);
}

TEST(Shapiro, NormalScoresAreNotRejected) {
  // x = qnorm(ppoints(30)): W = 0.99881534519112092 in R, p ~ 1.
  std::vector<double> z;
  const boost::math::normal_distribution<double> n01;
  for (int i = 1; i <= 30; ++i) z.push_back(quantile(n01, (i - 0.5) / 30.0));
  const auto r = ShapiroWilk(z);
  EXPECT_NEAR(r.W, 0.99881534519112092, 1e-9);
  EXPECT_GT(r.p, 0.999);
}

TEST(Shapiro, RefusesWhatItCannotTest) {
  EXPECT_ANY_THROW(ShapiroWilk({1.0, 2.0}));       // n < 3
  EXPECT_ANY_THROW(ShapiroWilk({2.0, 2.0, 2.0}));  // no spread
}

}  // namespace
}  // namespace hapticlab::stats::shapiro_test
