// Kruskal-Wallis against R 4.2.2's kruskal.test (options(digits = 17)); the grouping
// against the real-real limits is tested with the report (tests/stats/report_test.cpp).
#include "hapticlab/stats/nonparametric.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::stats::nonparametric_test {
namespace {

LongTable Groups(const std::vector<std::string>& g, const std::vector<double>& y) {
  LongTable t;
  t.key_names = {"material"};
  t.keys = {g};
  t.y = y;
  return t;
}

TEST(Nonparametric, KruskalWallisWithTiesMatchesR) {
  // y <- c(2.9, 3.0, 2.5, 2.6, 3.2, 3.8, 2.7, 4.0, 2.4, 2.8, 3.4, 3.7, 2.2, 2.0, 3.0)
  // g <- factor(c(rep("a", 5), rep("b", 4), rep("c", 6))); kruskal.test(y, g)
  const std::vector<double> y = {2.9, 3.0, 2.5, 2.6, 3.2, 3.8, 2.7, 4.0,
                                 2.4, 2.8, 3.4, 3.7, 2.2, 2.0, 3.0};
  std::vector<std::string> g;
  for (int i = 0; i < 15; ++i) g.push_back(i < 5 ? "a" : i < 9 ? "b" : "c");
  const auto k = KruskalWallis(Groups(g, y), "material");
  EXPECT_EQ(k.N, 15);
  EXPECT_EQ(k.df, 2.0);
  EXPECT_NEAR(k.H, 0.61568276684555989, 1e-12);
  EXPECT_NEAR(k.p, 0.73503189700679428, 1e-10);
  // One tie (3.0 twice): C = 1 - (2^3 - 2) / (15^3 - 15).
  EXPECT_NEAR(k.tie_correction, 0.99821428571428572, 1e-14);
  EXPECT_NEAR(k.H_uncorrected, 0.6145833333333357, 1e-12);
  // Dunn: every pair once, Bonferroni-adjusted p never below the raw one and at most 1.
  ASSERT_EQ(k.dunn.size(), 3u);
  for (const auto& d : k.dunn) {
    EXPECT_GE(d.p_adj, d.p);
    EXPECT_LE(d.p_adj, 1.0);
    EXPECT_NEAR(d.p_adj, std::min(1.0, 3 * d.p), 1e-15);
  }
}

TEST(Nonparametric, RefusesOneGroupAndAllTiedValues) {
  EXPECT_THROW(KruskalWallis(Groups({"a", "a", "a"}, {1, 2, 3}), "material"), InputError);
  EXPECT_THROW(KruskalWallis(Groups({"a", "b", "a", "b"}, {2, 2, 2, 2}), "material"), InputError);
}

}  // namespace
}  // namespace hapticlab::stats::nonparametric_test
