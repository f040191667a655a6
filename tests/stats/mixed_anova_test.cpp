// Mixed (between x within) ANOVA and its Tukey comparisons against afex/emmeans values in
// tests/data/stats/mixed_anova.json (made by tests/data/stats/mixed_anova.R from the CSVs
// beside it: 2 groups of 7 and 9 (+1 dropped) x 3 methods; 2 x 2 unbalanced groups x 3 x 2).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/stats/tukey.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::mixed_anova_test {
namespace {

using nlohmann::json;

json Ref(const char* design) {
  std::ifstream f(test::DataPath("stats/mixed_anova.json"));
  return json::parse(f)[design];
}

void ExpectRel(double got, const json& want, double tol, const std::string& what) {
  ASSERT_FALSE(want.is_null()) << what;
  const double w = want.get<double>();
  EXPECT_NEAR(got, w, tol * std::abs(w)) << what;
}

void CompareAnova(const RmAnovaResult& r, const json& ref) {
  ASSERT_EQ(r.effects.size(), ref.size());
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const auto& e = r.effects[i];
    const auto& w = ref[i];
    const std::string name = w["effect"].get<std::string>();
    ASSERT_EQ(e.effect, name);
    EXPECT_EQ(e.df1, w["df1"].get<double>()) << name;
    EXPECT_EQ(e.df2, w["df2"].get<double>()) << name;
    ExpectRel(e.SS, w["SS"], 1e-10, name + " SS");
    ExpectRel(e.SS_error, w["SS_error"], 1e-10, name + " SS_error");
    ExpectRel(e.F, w["F"], 1e-10, name + " F");
    ExpectRel(e.p, w["p"], 1e-9, name + " p");
    ExpectRel(e.pes, w["pes"], 1e-10, name + " pes");
    if (w["gg_epsilon"].is_null()) {
      // A between term, or a 1-df within term: afex prints no sphericity correction.
      EXPECT_EQ(e.gg_epsilon, 1.0) << name;
      continue;
    }
    ExpectRel(e.gg_epsilon, w["gg_epsilon"], 1e-10, name + " GG eps");
    ExpectRel(e.hf_epsilon, w["hf_epsilon"], 1e-10, name + " HF eps");
    ExpectRel(e.p_gg, w["p_gg"], 1e-9, name + " p GG");
    ExpectRel(e.p_hf, w["p_hf"], 1e-9, name + " p HF");
    ExpectRel(e.mauchly_W, w["mauchly_W"], 1e-10, name + " Mauchly W");
    ExpectRel(e.mauchly_p, w["mauchly_p"], 1e-9, name + " Mauchly p");
  }
}

// emmeans labels "x - y" with estimate mean(x) - mean(y); ours is a - b.
void ComparePairs(const TukeyResult& t, const json& ref) {
  ASSERT_EQ(t.pairs.size(), ref.size());
  for (const auto& w : ref) {
    const std::string c = w["contrast"].get<std::string>();
    const auto dash = c.find(" - ");
    const std::string x = c.substr(0, dash), y = c.substr(dash + 3);
    const TukeyPair* p = nullptr;
    double sign = 1;
    for (const auto& q : t.pairs) {
      if (q.a == x && q.b == y) p = &q;
      if (q.a == y && q.b == x) p = &q, sign = -1;
    }
    ASSERT_NE(p, nullptr) << c;
    ExpectRel(sign * p->diff, w["estimate"], 1e-10, c + " estimate");
    ExpectRel(p->se, w["SE"], 1e-10, c + " SE");
    EXPECT_EQ(p->df, w["df"].get<double>()) << c;
    // The t ratio decides the p-value; R's ptukey is accurate to ~1e-9 absolute here (our
    // ptukey is checked against high-precision quadrature in tukey_accuracy_test.cpp).
    EXPECT_NEAR(p->q / std::sqrt(2.0), std::abs(w["t"].get<double>()),
                1e-10 * std::abs(w["t"].get<double>()))
        << c;
    EXPECT_NEAR(p->p_adj, w["p"].get<double>(), 1e-8 + 1e-6 * w["p"].get<double>()) << c;
  }
}

TEST(MixedAnova, TwoGroupsOfUnequalSizeByThreeMethodsAgreeWithAfex) {
  const auto ref = Ref("a");
  const auto t =
      ReadLongCsv(test::DataPath("stats/mixed_2x3.csv"), "score", {"subject", "group", "method"});
  const auto r = RmAnova(t, "subject", {"method"}, {"group"});
  EXPECT_EQ(r.subjects.size(), ref["n_kept"].get<std::size_t>());
  ASSERT_EQ(r.dropped_subjects, std::vector<std::string>{ref["dropped"].get<std::string>()});
  EXPECT_EQ(r.dropped_reasons.at(0), "no rating for method=visual");
  EXPECT_EQ(r.group_sizes, (std::vector<int>{9, 7}));  // expert, novice (sorted)
  EXPECT_EQ(r.error_df, 14);
  CompareAnova(r, ref["anova"]);
  ComparePairs(TukeyWithin(r, "group", true), ref["tukey_group"]);
  ComparePairs(TukeyWithin(r, "method", true), ref["tukey_method_multivariate"]);
  ComparePairs(TukeyWithin(r, "method", false), ref["tukey_method_univariate"]);
}

TEST(MixedAnova, TwoBetweenByTwoWithinFactorsUnbalancedAgreeWithAfex) {
  const auto ref = Ref("b");
  const auto t = ReadLongCsv(test::DataPath("stats/mixed_2x2x3x2.csv"), "score",
                             {"subject", "group", "lab", "method", "material"});
  const auto r = RmAnova(t, "subject", {"method", "material"}, {"group", "lab"});
  EXPECT_EQ(r.subjects.size(), ref["n_kept"].get<std::size_t>());
  EXPECT_TRUE(r.dropped_subjects.empty());
  CompareAnova(r, ref["anova"]);
  ComparePairs(TukeyWithin(r, "group", true), ref["tukey_group"]);
  ComparePairs(TukeyWithin(r, "method", true), ref["tukey_method_multivariate"]);
}

TEST(MixedAnova, ABetweenFactorGivenAsWithinIsNamed) {
  const auto t =
      ReadLongCsv(test::DataPath("stats/mixed_2x3.csv"), "score", {"subject", "group", "method"});
  try {
    RmAnova(t, "subject", {"group", "method"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'group' is a between-subjects factor"), std::string::npos) << m;
    EXPECT_NE(m.find("give it as a between factor"), std::string::npos) << m;
  }
  // And a within factor given as between.
  try {
    RmAnova(t, "subject", {}, {"method"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'method' varies within subject"), std::string::npos)
        << e.what();
  }
}

TEST(MixedAnova, AMissingScoreDropsItsSubjectByName) {
  auto t =
      ReadLongCsv(test::DataPath("stats/mixed_2x3.csv"), "score", {"subject", "group", "method"});
  // S03's first audio rating missing: its audio cell is unobserved, so S03 goes (as afex).
  std::size_t row = 0;
  while (!(t.keys[0][row] == "S03" && t.keys[2][row] == "audio")) ++row;
  t.y[row] = std::numeric_limits<double>::quiet_NaN();
  const auto r = RmAnova(t, "subject", {"method"}, {"group"});
  EXPECT_EQ(r.dropped_subjects, (std::vector<std::string>{"S03", "S17"}));
  EXPECT_NE(r.dropped_reasons.at(0).find("missing score"), std::string::npos)
      << r.dropped_reasons.at(0);
  EXPECT_EQ(r.subjects.size(), 15u);
}

TEST(MixedAnova, AnEmptyBetweenCellIsAnError) {
  const auto all =
      ReadLongCsv(test::DataPath("stats/mixed_2x3.csv"), "score", {"subject", "group", "method"});
  // The only novice left, S01, misses its visual ratings: the novice cell is empty.
  LongTable t = all;
  t.keys.assign(3, {});
  t.y.clear();
  for (std::size_t r = 0; r < all.rows(); ++r) {
    const bool novice = all.keys[1][r] == "novice";
    if (novice && (all.keys[0][r] != "S01" || all.keys[2][r] == "visual")) continue;
    for (std::size_t c = 0; c < 3; ++c) t.keys[c].push_back(all.keys[c][r]);
    t.y.push_back(all.y[r]);
  }
  try {
    RmAnova(t, "subject", {"method"}, {"group"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("between cell group=novice"), std::string::npos)
        << e.what();
  }
}

// The residuals the report's normality check tests are afex's residuals() of the aov_ez fit,
// and Shapiro-Wilk on them is R's shapiro.test(residuals(fit)), on two of afex's real data
// sets (tests/data/stats/residuals_reference.R wrote the CSVs and the JSON).
void CompareResiduals(const RmAnovaResult& r, const json& ref) {
  auto mine = AnovaResiduals(r);
  std::vector<double> theirs;
  for (const auto& row : ref["residuals"]) theirs.push_back(row["residual"].get<double>());
  ASSERT_EQ(mine.size(), theirs.size());
  ASSERT_EQ(static_cast<int>(mine.size()), ref["n"].get<int>());
  std::sort(mine.begin(), mine.end());
  std::sort(theirs.begin(), theirs.end());
  for (std::size_t i = 0; i < mine.size(); ++i) EXPECT_NEAR(mine[i], theirs[i], 1e-9) << i;
  const auto sw = ShapiroWilk(AnovaResiduals(r));
  EXPECT_NEAR(sw.W, ref["W"].get<double>(), 1e-12);
  EXPECT_NEAR(sw.p, ref["p"].get<double>(), 1e-9);
}

json ResidualRef(const char* data_set) {
  std::ifstream f(test::DataPath("stats/residuals_reference.json"));
  return json::parse(f)[data_set];
}

TEST(AnovaResiduals, WithinDesignEqualsAfexAndShapiroTestOnMd121) {
  const auto t = ReadLongCsv(test::DataPath("stats/md_12_1.csv"), "rt", {"id", "angle", "noise"});
  CompareResiduals(RmAnova(t, "id", {"angle", "noise"}), ResidualRef("md_12_1"));
}

TEST(AnovaResiduals, MixedDesignEqualsAfexAndShapiroTestOnObrienKaiser) {
  // Residuals are taken from the cell means of each between group (treatment x gender).
  const auto t = ReadLongCsv(test::DataPath("stats/obk_long.csv"), "value",
                             {"id", "treatment", "gender", "phase", "hour"});
  CompareResiduals(RmAnova(t, "id", {"phase", "hour"}, {"treatment", "gender"}),
                   ResidualRef("obk_long"));
}

}  // namespace
}  // namespace hapticlab::stats::mixed_anova_test
