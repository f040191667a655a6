// The mixed-model formula parser (lmm_design.cpp): R's term order and its refusals.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/lmm.hpp"

namespace hapticlab::stats {
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
  EXPECT_THROW(ParseLmmFormula("score ~ a", "f.csv"), InputError);  // no random term
  EXPECT_THROW(ParseLmmFormula("score ~ a - 1 + (1 | g)", "f.csv"), InputError);
  EXPECT_THROW(ParseLmmFormula("score a + (1 | g)", "f.csv"), InputError);
}

}  // namespace
}  // namespace hapticlab::stats
