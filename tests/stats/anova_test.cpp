// Properties of the ANOVA, Tukey and grouping code beyond the R fixtures.

#include "hapticlab/stats/anova.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/descriptive.hpp"
#include "hapticlab/stats/distributions.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "hapticlab/stats/tukey.hpp"
#include "long_table_fixture.hpp"

namespace hapticlab::stats::anova_test {
namespace {

using fixture::Make;

TEST(RmAnova, TwoLevelFactorIsAPairedTTestWithTrivialSphericity) {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> g(0, 1);
  std::vector<std::tuple<std::string, std::string, double>> rows;
  std::vector<double> d;
  for (int s = 0; s < 12; ++s) {
    const double base = g(rng), a = base + g(rng), b = base + 0.7 + g(rng);
    rows.push_back({"S" + std::to_string(s), "a", a});
    rows.push_back({"S" + std::to_string(s), "b", b});
    d.push_back(b - a);
  }
  const auto r = RmAnova(Make(rows), "subject", {"cond"});
  const auto& e = r.effects.at(0);
  const auto desc = Describe(d);
  const double t = desc.mean / desc.se;
  EXPECT_NEAR(e.F, t * t, 1e-10);
  EXPECT_NEAR(e.p, PtTwoSided(t, 11), 1e-12);
  EXPECT_TRUE(e.mauchly_defined);
  EXPECT_EQ(e.mauchly_W, 1.0);
  EXPECT_EQ(e.gg_epsilon, 1.0);
  EXPECT_EQ(e.hf_epsilon, 1.0);
  EXPECT_NEAR(e.p_gg, e.p, 1e-15);
}

TEST(RmAnova, SubjectsWithAMissingCellAreDroppedAndRepetitionsAveraged) {
  const auto r = RmAnova(Make({{"S1", "a", 1},
                               {"S1", "a", 3},
                               {"S1", "b", 4},
                               {"S1", "c", 5},
                               {"S2", "a", 2},
                               {"S2", "b", 2},
                               {"S2", "c", 7},
                               {"S3", "a", 1},
                               {"S3", "b", 6},
                               {"S3", "c", 2},
                               {"S4", "a", 9},
                               {"S4", "b", 1}}),
                         "subject", {"cond"});
  EXPECT_EQ(r.subjects, (std::vector<std::string>{"S1", "S2", "S3"}));
  EXPECT_EQ(r.dropped_subjects, std::vector<std::string>{"S4"});
  EXPECT_DOUBLE_EQ(r.cells[0][0], 2.0);  // mean of the two repetitions
}

TEST(RmAnova, ErrorsNameTheProblem) {
  EXPECT_THROW(RmAnova(Make({{"S1", "a", 1}, {"S1", "b", 2}}), "subject", {"cond"}), InputError);
  EXPECT_THROW(RmAnova(Make({{"S1", "a", 1}, {"S2", "a", 2}}), "subject", {"cond"}), InputError);
  EXPECT_THROW(RmAnova(Make({{"S1", "a", 1}}), "subject", {"nope"}), InputError);
}

TEST(Correction, UsedPFollowsAfexsNamesAndLeavesBetweenEffectsAlone) {
  AnovaEffect within{.effect = "m", .df1 = 4, .df2 = 8, .p = 0.02};
  within.gg_epsilon = 0.3;
  within.p_gg = 0.12;
  within.hf_epsilon = 0.5;
  within.hf_epsilon_used = 0.5;
  within.p_hf = 0.07;
  EXPECT_EQ(UsedP(within, ParseCorrection("GG", "f", "c")), 0.12);
  EXPECT_EQ(UsedP(within, ParseCorrection("HF", "f", "c")), 0.07);
  EXPECT_EQ(UsedP(within, ParseCorrection("none", "f", "c")), 0.02);
  EXPECT_EQ(UsedEpsilon(within, Correction::kGG), 0.3);
  EXPECT_EQ(UsedEpsilon(within, Correction::kNone), 1.0);
  AnovaEffect between{.effect = "g", .between_only = true, .df1 = 1, .df2 = 8, .p = 0.04};
  between.p_gg = between.p_hf = 0.04;
  EXPECT_EQ(UsedP(between, Correction::kGG), 0.04);
  EXPECT_EQ(UsedEpsilon(between, Correction::kHF), 1.0);
  EXPECT_THROW(ParseCorrection("gg", "f", "c"), InputError);
  EXPECT_STREQ(CorrectionName(Correction::kHF), "HF");
}

// Levels b and c a constant apart in every subject: one contrast has no error variance, so
// the error covariance is singular with fewer contrasts than error df. Mauchly's W is 0 and
// its p 0 (R's mauchly.test: chi2 = Inf), not a library error.
TEST(RmAnova, AContrastWithoutErrorVarianceGivesMauchlysWZero) {
  std::vector<std::tuple<std::string, std::string, double>> rows;
  const double a[] = {1, 5, 2, 8, 3}, b[] = {4, 2, 6, 3, 7};
  for (int s = 0; s < 5; ++s) {
    const std::string subject = "S" + std::to_string(s + 1);
    const auto i = static_cast<std::size_t>(s);
    rows.push_back({subject, "a", a[i]});
    rows.push_back({subject, "b", b[i]});
    rows.push_back({subject, "c", b[i] + 1});
  }
  const auto r = RmAnova(Make(rows), "subject", {"cond"});
  ASSERT_EQ(r.effects.size(), 1u);
  const auto& e = r.effects[0];
  EXPECT_TRUE(std::isfinite(e.F));
  EXPECT_LT(e.mauchly_W, 1e-10);
  EXPECT_LT(e.mauchly_p, 1e-10);
  EXPECT_GT(e.gg_epsilon, 0.5 - 1e-12);  // the lower bound 1 / (k - 1)
  EXPECT_LE(e.gg_epsilon, 1.0);
}

}  // namespace
}  // namespace hapticlab::stats::anova_test
