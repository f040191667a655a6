// The whole analysis of a synthetic study (tests/data/stats/example_raw.csv) against what R
// computes on it (example_output.json, made by tools/stats_oracle.R with R 4.2.2, afex 1.2.1,
// emmeans 1.8.4, rstatix 0.7.2): agreement to 1e-6 relative.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/descriptive.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/stats/tukey.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::stats::example_study_test {
namespace {

using nlohmann::json;

// 1e-6 relative: the agreement criterion.
constexpr double kRel = 1e-6;

void Near(double got, double want, const std::string& what) {
  EXPECT_LE(std::abs(got - want), kRel * std::abs(want) + 1e-300)
      << what << ": got " << got << " want " << want;
}

// R's Tukey p-values come from its ptukey as 1 - lower tail, whose absolute accuracy is
// ~1e-12 at best (vectors.csv rows 14-16; our ptukey is checked there against a
// high-precision reference to 1e-6 relative down to 1e-23). So p-values from R get
// 1e-6 relative plus 1e-11 absolute.
void NearTukeyP(double got, double want, const std::string& what) {
  EXPECT_LE(std::abs(got - want), kRel * std::abs(want) + 1e-11)
      << what << ": got " << got << " want " << want;
}

class ExampleStudy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::ifstream f(test::DataPath("stats/example_output.json"));
    ref_ = new json(json::parse(f));
    raw_ = new LongTable(ReadLongCsv(test::DataPath("stats/example_raw.csv"), "score",
                                     {"subject", "method", "material", "criterion"}));
  }
  static void TearDownTestSuite() {
    delete ref_;
    delete raw_;
  }
  static const json& R(const std::string& crit) { return (*ref_)["criteria"][crit]; }
  static LongTable Crit(const std::string& crit) { return raw_->Where({{"criterion", crit}}); }
  static json* ref_;
  static LongTable* raw_;
};
json* ExampleStudy::ref_ = nullptr;
LongTable* ExampleStudy::raw_ = nullptr;

const AnovaEffect& Effect(const RmAnovaResult& a, const std::string& name) {
  for (const auto& e : a.effects)
    if (e.effect == name) return e;
  throw std::runtime_error("no effect " + name);
}

TEST_F(ExampleStudy, TwoWayRmAnovaUncorrectedGreenhouseGeisserHuynhFeldt) {
  for (const std::string crit : {"realism", "similarity"}) {
    SCOPED_TRACE(crit);
    const auto a = RmAnova(Crit(crit), "subject", {"method", "material"});
    const auto& r = R(crit)["two_way_rm"];
    ASSERT_EQ(a.effects.size(), 3u);
    for (const auto& row : r["none"]) {
      const auto& e = Effect(a, row["effect"]);
      Near(e.df1, row["df1"], e.effect + " df1");
      Near(e.df2, row["df2"], e.effect + " df2");
      Near(e.MSE, row["MSE"], e.effect + " MSE");
      Near(e.F, row["F"], e.effect + " F");
      Near(e.pes, row["pes"], e.effect + " pes");
      Near(e.p, row["p"], e.effect + " p");
    }
    if (!r["mauchly"].is_null())
      for (const auto& row : r["mauchly"]) {
        const auto& e = Effect(a, row["effect"]);
        ASSERT_TRUE(e.mauchly_defined) << e.effect;
        Near(e.mauchly_W, row["W"], e.effect + " W");
        Near(e.mauchly_p, row["p_R"], e.effect + " mauchly p (R, second order)");
        Near(e.mauchly_chi2, row["chisq"], e.effect + " chi2");
        Near(e.mauchly_p_firstorder, row["p_firstorder"], e.effect + " first-order p");
      }
    if (!r["epsilons"].is_null())
      for (const auto& row : r["epsilons"]) {
        const auto& e = Effect(a, row["effect"]);
        Near(e.gg_epsilon, row["GG_eps"], e.effect + " GG eps");
        Near(e.p_gg, row["p_GG"], e.effect + " p GG");
        Near(e.hf_epsilon, row["HF_eps"], e.effect + " HF eps (uncapped)");
        Near(e.p_hf, row["p_HF"], e.effect + " p HF");
      }
    // Where the covariance is singular R has no test; epsilons from the direct computation.
    for (const auto& row : r["gg_manual"]) {
      const auto& e = Effect(a, row["effect"]);
      Near(e.gg_epsilon, row["GG_eps"], e.effect + " GG eps (direct)");
      Near(e.hf_epsilon, row["HF_eps_uncapped"], e.effect + " HF eps (direct)");
    }
    const auto& inter = Effect(a, "method:material");
    EXPECT_FALSE(inter.mauchly_defined);  // 18 df > 10 subjects - 1
    EXPECT_TRUE(std::isnan(inter.mauchly_W));
    for (const auto& row : r["GG"]) {
      const auto& e = Effect(a, row["effect"]);
      if (!e.mauchly_defined) continue;  // afex prints uncorrected df there; we do not
      Near(e.df1 * e.gg_epsilon, row["df1"], e.effect + " GG df1");
      Near(e.df2 * e.gg_epsilon, row["df2"], e.effect + " GG df2");
      Near(e.MSE / e.gg_epsilon, row["MSE"], e.effect + " GG MSE");
    }
  }
}

TEST_F(ExampleStudy, OneWayOnMethodAveragesTheOtherFactor) {
  const auto a = RmAnova(Crit("realism"), "subject", {"method"});
  const auto& r = R("realism")["one_way_rm_method"];
  const auto& e = a.effects.at(0);
  Near(e.F, r["none"][0]["F"], "F");
  Near(e.MSE, r["none"][0]["MSE"], "MSE");
  Near(e.p, r["none"][0]["p"], "p");
  Near(e.p_gg, r["GG"][0]["p"], "p GG");
  Near(e.mauchly_W, r["mauchly"][0]["W"], "W");
}

TEST_F(ExampleStudy, TukeyWithinUnivariateAndMultivariateMatchEmmeans) {
  const auto a = RmAnova(Crit("realism"), "subject", {"method", "material"});
  for (const bool mv : {false, true}) {
    const auto t = TukeyWithin(a, "method", mv);
    const auto& rows =
        R("realism")["emmeans_tukey_within"][mv ? "method_multivariate" : "method_univariate"];
    ASSERT_EQ(t.pairs.size(), rows.size());
    for (const auto& row : rows) {
      // emmeans "b - a" with estimate = mean(b) - mean(a); ours: a = later level, diff = a - b.
      const std::string c = row["contrast"];
      const auto dash = c.find(" - ");
      const std::string first = c.substr(0, dash), second = c.substr(dash + 3);
      const TukeyPair* p = nullptr;
      for (const auto& x : t.pairs)
        if (x.b == first && x.a == second) p = &x;
      ASSERT_NE(p, nullptr) << c;
      Near(-p->diff, row["estimate"], c + " estimate");
      Near(p->se, row["SE"], c + " SE");
      Near(p->df, row["df"], c + " df");
      Near(-p->diff / p->se, row["t"], c + " t");
      NearTukeyP(p->p_adj, row["p_adj"], c + " p_adj");
    }
  }
}

TEST_F(ExampleStudy, TukeyHsdBetweenOnCellAndSubjectMeans) {
  const auto cells = Crit("realism").Average({"subject", "method", "material"});
  const auto subj = cells.Average({"subject", "method"});
  for (const auto& [data, key] : {std::pair{cells, "on_cell_means"}, {subj, "on_subject_means"}}) {
    SCOPED_TRACE(key);
    const auto t = TukeyBetween(data, "method");
    const auto& r = R("realism")["tukey_hsd_between"][key];
    Near(t.mse, r["MSE"], "MSE");
    Near(t.df, r["df_error"], "df");
    for (const auto& row : r["pairs"]) {
      const std::string c = row["contrast"];
      const TukeyPair* p = nullptr;
      for (const auto& x : t.pairs)
        if (x.a + "-" + x.b == c) p = &x;
      ASSERT_NE(p, nullptr) << c;
      Near(p->diff, row["diff"], c + " diff");
      Near(p->lwr, row["lwr"], c + " lwr");
      Near(p->upr, row["upr"], c + " upr");
      Near(p->q, row["q"], c + " q");
      NearTukeyP(p->p_adj, row["p_adj"], c + " p_adj");
    }
  }
}

TEST_F(ExampleStudy, KruskalWallisAndDunnBonferroni) {
  const auto raw = Crit("realism");
  const auto cells = raw.Average({"subject", "method", "material"});
  for (const auto& [data, key] : {std::pair{cells, "on_cell_means"}, {raw, "on_raw"}}) {
    SCOPED_TRACE(key);
    const auto k = KruskalWallis(data, "method");
    const auto& r = R("realism")["kruskal_wallis"][key];
    Near(k.H, r["H"], "H");
    Near(k.df, r["df"], "df");
    Near(k.p, r["p"], "p");
    Near(k.H_uncorrected, r["H_uncorrected"], "H uncorrected");
    Near(k.tie_correction, r["tie_correction_C"], "tie correction");
  }
  const auto k = KruskalWallis(cells, "method");
  for (const auto& row : R("realism")["dunn_bonferroni"]["on_cell_means"]) {
    const DunnPair* d = nullptr;
    for (const auto& x : k.dunn)
      if (x.a == row["group1"] && x.b == row["group2"]) d = &x;
    ASSERT_NE(d, nullptr);
    Near(d->z, row["statistic"], "z");
    Near(d->p, row["p"], "p");
    Near(d->p_adj, row["p.adj"], "p.adj");
  }
}

TEST_F(ExampleStudy, ShapiroOutliersDescriptivesCorrelation) {
  const auto raw = Crit("realism");
  const auto& r = R("realism");
  const auto all = ShapiroWilk(raw.y);
  Near(all.W, r["shapiro"]["all_raw"]["W"], "W raw");
  Near(all.p, r["shapiro"]["all_raw"]["p"], "p raw");
  const auto cells = raw.Average({"subject", "method", "material"});
  for (const auto& m : cells.Levels("method")) {
    const auto g = cells.Where({{"method", m}});
    const auto s = ShapiroWilk(g.y);
    Near(s.W, r["shapiro"]["per_method_cell_means"][m]["W"], m + " W");
    Near(s.p, r["shapiro"]["per_method_cell_means"][m]["p"], m + " p");
    const auto d = Describe(g.y);
    for (const auto& row : r["descriptives_method_cell_means"])
      if (row["level"] == m) {
        Near(d.mean, row["mean"], m + " mean");
        Near(d.sd, row["sd"], m + " sd");
        Near(d.se, row["se"], m + " se");
        Near(d.median, row["median"], m + " median");
        Near(d.ci95_lo, row["ci95_lo"], m + " ci lo");
        Near(d.ci95_hi, row["ci95_hi"], m + " ci hi");
      }
    const auto graw = raw.Where({{"method", m}});
    for (const auto& [rule, key] :
         {std::pair{QuartileRule::kHinges, "hinges"}, {QuartileRule::kType7, "type7"}}) {
      const auto o = Outliers(graw.y, rule);
      const auto& ro = r["outliers_1.5IQR_per_method_raw"][m][key];
      Near(o.q1, ro["q1"], m + " q1 " + key);
      Near(o.q3, ro["q3"], m + " q3 " + key);
      Near(o.lower, ro["lower"], m + " lower " + key);
      Near(o.upper, ro["upper"], m + " upper " + key);
      EXPECT_EQ(o.outliers.size(), ro["n_out"].get<std::size_t>()) << m << " " << key;
    }
  }
  // Realism vs similarity on matching cell means.
  const auto x = raw.Average({"subject", "method", "material"});
  const auto y = Crit("similarity").Average({"subject", "method", "material"});
  ASSERT_EQ(x.keys, y.keys);
  const auto pc = Pearson(x.y, y.y);
  const auto& rc = (*ref_)["correlation"];
  Near(pc.r, rc["pearson"]["estimate"], "pearson r");
  Near(pc.t, rc["pearson"]["statistic"], "pearson t");
  Near(pc.p, rc["pearson"]["p"], "pearson p");
  // Spearman: rank statistics tie values equal to 9 decimals. Two of these cell means are
  // equal in exact arithmetic but differ in R's last bit, so R breaks that tie and its rho
  // is 1.2e-5 higher. Exact-arithmetic rho of this data (ranks of the means computed with
  // rational numbers): 0.09407555631566358.
  const auto sc = Spearman(x.y, y.y);
  EXPECT_NEAR(sc.r, 0.09407555631566358, 1e-12);
  EXPECT_NEAR(sc.r, rc["spearman"]["estimate"].get<double>(), 2e-5);
}

}  // namespace
}  // namespace hapticlab::stats::example_study_test
