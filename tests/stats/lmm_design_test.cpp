// The mixed-model formula parser (lmm_formula.cpp): R's term order and its refusals.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/lmm.hpp"

namespace hapticlab::stats::lmm_design_test {
namespace {

TEST(Lmm, FormulaParsing) {
  const auto f = ParseLmmFormula("score ~ a * b + c + (1 + a | g) + (0 + x | h)");
  EXPECT_EQ(f.response, "score");
  ASSERT_EQ(f.fixed.size(), 4u);  // a, b, c, a:b (R's order: by degree)
  EXPECT_EQ(f.fixed[2], std::vector<std::string>{"c"});
  EXPECT_EQ(f.fixed[3], (std::vector<std::string>{"a", "b"}));
  ASSERT_EQ(f.random.size(), 2u);
  EXPECT_TRUE(f.random[0].intercept);
  EXPECT_FALSE(f.random[1].intercept);
  EXPECT_EQ(f.random[1].group, "h");
  EXPECT_THROW(ParseLmmFormula("score ~ a + (1 | )", "f.csv"), InputError);
  EXPECT_THROW(ParseLmmFormula("score ~ a", "f.csv"), InputError);                // no random term
  EXPECT_THROW(ParseLmmFormula("score ~ a - b + (1 | g)", "f.csv"), InputError);  // only - 1
  EXPECT_THROW(ParseLmmFormula("score ~ a^2 + (1 | g)", "f.csv"), InputError);    // not in I()
  EXPECT_THROW(ParseLmmFormula("score ~ foo(a) + (1 | g)", "f.csv"), InputError);
  EXPECT_THROW(ParseLmmFormula("score ~ I(a + (1 | g)", "f.csv"), InputError);
  EXPECT_THROW(ParseLmmFormula("score a + (1 | g)", "f.csv"), InputError);
}

// lme4's expansions and R's names for functions of columns.
TEST(Lmm, FormulaLanguage) {
  const auto f = ParseLmmFormula("log(y) ~ 0 + I(x^2) + scale(x)*c + (x || s) + (1 | a/b)");
  EXPECT_EQ(f.response, "y");
  EXPECT_EQ(f.response_term, "log(y)");
  EXPECT_FALSE(f.intercept);
  ASSERT_EQ(f.fixed.size(), 4u);
  EXPECT_EQ(f.fixed[0], std::vector<std::string>{"I(x^2)"});
  EXPECT_EQ(f.fixed[3], (std::vector<std::string>{"scale(x)", "c"}));
  ASSERT_EQ(f.random.size(), 4u);  // (1 | s), (0 + x | s), (1 | b:a), (1 | a)
  EXPECT_TRUE(f.random[0].intercept);
  EXPECT_TRUE(f.random[0].terms.empty());
  EXPECT_FALSE(f.random[1].intercept);
  EXPECT_EQ(f.random[1].terms, std::vector<std::vector<std::string>>{{"x"}});
  EXPECT_EQ(f.random[2].group, "b:a");
  EXPECT_EQ(f.random[2].group_factors, (std::vector<std::string>{"b", "a"}));
  EXPECT_EQ(f.random[3].group, "a");
  EXPECT_EQ(f.Columns(), (std::vector<std::string>{"y", "x", "c", "s", "b", "a"}));
  EXPECT_TRUE(ParseLmmFormula("y ~ x - 1 + (1 | g)").intercept == false);
  EXPECT_TRUE(ParseLmmFormula("y ~ -1 + x + 1 + (1 | g)").intercept);
  // R's deparse: spaces around + - *, none around / ^.
  EXPECT_EQ(ParseLmmFormula("y ~ I(x*2-1/3) + log(x+1) + (1 | g)").fixed[0][0], "I(x * 2 - 1/3)");
  EXPECT_EQ(ParseLmmFormula("y ~ I(x*2-1/3) + log(x+1) + (1 | g)").fixed[1][0], "log(x + 1)");
}

}  // namespace
}  // namespace hapticlab::stats::lmm_design_test
