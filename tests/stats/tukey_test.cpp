// Tukey HSD and the compact letter grouping (stats/src/tukey.cpp).

#include "hapticlab/stats/tukey.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/descriptive.hpp"
#include "hapticlab/stats/distributions.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "long_table_fixture.hpp"

namespace hapticlab::stats::tukey_test {
namespace {

using fixture::Make;

TEST(Tukey, EqualGroupsGiveTheClassicalHsd) {
  // Three groups of 5: q = |diff| / sqrt(MSE / n).
  const auto t = TukeyBetween(Make({{"1", "x", 1},
                                    {"2", "x", 2},
                                    {"3", "x", 3},
                                    {"4", "x", 2},
                                    {"5", "x", 2},
                                    {"6", "y", 4},
                                    {"7", "y", 5},
                                    {"8", "y", 6},
                                    {"9", "y", 5},
                                    {"10", "y", 5},
                                    {"11", "z", 2},
                                    {"12", "z", 3},
                                    {"13", "z", 4},
                                    {"14", "z", 3},
                                    {"15", "z", 3}}),
                              "cond");
  EXPECT_DOUBLE_EQ(t.mse, 0.5);
  ASSERT_EQ(t.pairs.size(), 3u);
  EXPECT_EQ(t.pairs[0].a, "y");
  EXPECT_EQ(t.pairs[0].b, "x");
  EXPECT_DOUBLE_EQ(t.pairs[0].diff, 3.0);
  EXPECT_NEAR(t.pairs[0].q, 3.0 / std::sqrt(0.5 / 5), 1e-12);
  EXPECT_NEAR(t.pairs[0].p_adj, PtukeyUpper(t.pairs[0].q, 3, 12), 1e-15);
  const double half = Qtukey(0.95, 3, 12) * std::sqrt(0.5 / 5);
  EXPECT_NEAR(t.pairs[0].upr - t.pairs[0].diff, half, 1e-9);
}

TEST(Grouping, LettersAgainstTheRealRealLimits) {
  // Upper limit ~78, lower ~35; "good" near the upper, "bad" near the lower, "mid" between
  // with too few data to differ from either.
  std::vector<std::tuple<std::string, std::string, double>> rows;
  std::mt19937_64 rng(9);
  std::normal_distribution<double> g(0, 5);
  auto add = [&](const char* c, double mean, int n) {
    for (int i = 0; i < n; ++i) rows.push_back({"S", c, mean + g(rng)});
  };
  add("upper", 78, 40);
  add("lower", 35, 40);
  add("good", 77, 40);
  add("bad", 36, 40);
  add("mid", 56, 3);
  add("odd", 56, 40);
  const auto groups = GroupAgainstLimits(Make(rows), "cond", "upper", "lower");
  std::map<std::string, std::string> letter;
  for (const auto& x : groups) letter[x.material] = x.letter;
  EXPECT_EQ(letter["good"], "A");
  EXPECT_EQ(letter["bad"], "B");
  EXPECT_EQ(letter["mid"], "C");
  EXPECT_EQ(letter["odd"], "D");
}

}  // namespace
}  // namespace hapticlab::stats::tukey_test
