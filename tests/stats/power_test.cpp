// Monte-Carlo power (stats/power.hpp) against the analytic power of a one-factor
// within-subjects design with compound symmetry (sphericity holds), where the F statistic of
// the rm-ANOVA follows a noncentral F(k-1, (k-1)(n-1), lambda) with
// lambda = n sum_j (mu_j - mu)^2 / sigma_e^2 (e.g. Maxwell & Delaney, ch. 11).
// The reference distribution is Boost.Math's non_central_f_distribution.

#include "hapticlab/stats/power.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/non_central_f.hpp>
#include <cmath>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::stats::power_test {
namespace {

constexpr double kSigmaE = 10, kSigmaSubject = 8;
const std::vector<double> kMu = {0, 4, 8};  // condition means

LongTable OneFactor(int n, Rng& rng) {
  LongTable t;
  t.key_names = {"participant", "criterion", "condition"};
  t.keys.assign(3, {});
  t.y_name = "score";
  for (int i = 0; i < n; ++i) {
    const double s = rng.Normal(0, kSigmaSubject);
    for (std::size_t j = 0; j < kMu.size(); ++j) {
      t.keys[0].push_back(fmt::format("S{:03d}", i));
      t.keys[1].push_back("overall");
      t.keys[2].push_back(fmt::format("c{}", j));
      t.y.push_back(50 + s + kMu[j] + rng.Normal(0, kSigmaE));
    }
  }
  return t;
}

double AnalyticPower(int n, double alpha) {
  const double k = static_cast<double>(kMu.size()), mean = (kMu[0] + kMu[1] + kMu[2]) / 3;
  double ss = 0;
  for (double m : kMu) ss += (m - mean) * (m - mean);
  const double lambda = n * ss / (kSigmaE * kSigmaE);
  const double df1 = k - 1, df2 = (k - 1) * (n - 1);
  const double fcrit =
      quantile(complement(boost::math::fisher_f_distribution<double>(df1, df2), alpha));
  return cdf(complement(boost::math::non_central_f_distribution<double>(df1, df2, lambda), fcrit));
}

TEST(StudyPower, MatchesTheNoncentralFWithinItsMonteCarloInterval) {
  PowerOptions o;
  o.participants = {6, 10, 16};
  o.simulations = 600;
  o.seed = 42;
  const auto r = SimulatePower("one-factor", OneFactor, o);
  ASSERT_EQ(r.rows.size(), 3u);
  for (const auto& row : r.rows) {
    ASSERT_EQ(row.effects.size(), 1u);
    const auto& e = row.effects[0];
    EXPECT_EQ(e.effect, "condition");
    EXPECT_EQ(e.runs, 600);
    double lo, hi;
    WilsonInterval(e.hits, e.runs, &lo, &hi);
    const double analytic = AnalyticPower(row.participants, 0.05);
    EXPECT_GT(analytic, 0.15);  // the design has power to detect: a real test, not one near alpha
    EXPECT_LE(lo, analytic) << row.participants << " participants: simulated " << e.power();
    EXPECT_GE(hi, analytic) << row.participants << " participants: simulated " << e.power();
  }
}

TEST(StudyPower, NullEffectRejectsAtAlpha) {
  PowerOptions o;
  o.participants = {10};
  o.simulations = 600;
  o.seed = 7;
  const auto r = SimulatePower(
      "null",
      [](int n, Rng& rng) {
        auto t = OneFactor(n, rng);
        for (std::size_t i = 0; i < t.rows(); ++i)
          t.y[i] -= kMu[static_cast<std::size_t>(t.keys[2][i][1] - '0')];
        return t;
      },
      o);
  double lo, hi;
  WilsonInterval(r.rows[0].effects[0].hits, r.rows[0].effects[0].runs, &lo, &hi);
  EXPECT_LE(lo, 0.05);
  EXPECT_GE(hi, 0.05);
}

TEST(StudyPower, ThreadsAndShardsGiveTheSameResult) {
  PowerOptions o;
  o.participants = {6, 9};
  o.simulations = 50;
  o.seed = 3;
  o.threads = 1;
  const std::string one = PowerToJson(SimulatePower("p", OneFactor, o));
  o.threads = 3;
  EXPECT_EQ(PowerToJson(SimulatePower("p", OneFactor, o)), one);
  std::vector<PowerResult> parts;
  for (int s = 0; s < 3; ++s) {
    o.shard = s;
    o.shards = 3;
    parts.push_back(PowerFromJson(PowerToJson(SimulatePower("p", OneFactor, o)), "part"));
  }
  // Sums of floating-point pes differ in the last bits with a different summation order;
  // counts must be exact.
  const auto merged = MergePower(parts, {"a", "b", "c"});
  const auto whole = PowerFromJson(one, "whole");
  ASSERT_EQ(merged.rows.size(), whole.rows.size());
  for (std::size_t i = 0; i < whole.rows.size(); ++i)
    for (std::size_t e = 0; e < whole.rows[i].effects.size(); ++e) {
      EXPECT_EQ(merged.rows[i].effects[e].hits, whole.rows[i].effects[e].hits);
      EXPECT_EQ(merged.rows[i].effects[e].runs, whole.rows[i].effects[e].runs);
      EXPECT_NEAR(merged.rows[i].effects[e].sum_pes, whole.rows[i].effects[e].sum_pes, 1e-9);
    }
  parts.pop_back();
  EXPECT_THROW(MergePower(parts, {"a", "b"}), InputError);
}

TEST(StudyPower, WilsonIntervalMatchesPublishedValues) {
  // R: prop.test(81, 263, correct = FALSE)$conf.int (the Wilson score interval) is
  // [0.255289, 0.366210]; prop.test(0, 20, correct = FALSE): [0, 0.161125].
  double lo, hi;
  WilsonInterval(81, 263, &lo, &hi);
  EXPECT_NEAR(lo, 0.2553, 5e-4);
  EXPECT_NEAR(hi, 0.3662, 5e-4);
  WilsonInterval(0, 20, &lo, &hi);
  EXPECT_NEAR(lo, 0, 1e-12);
  EXPECT_NEAR(hi, 0.1611, 5e-4);
}

}  // namespace
}  // namespace hapticlab::stats::power_test
