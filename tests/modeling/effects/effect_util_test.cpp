// effects/effect_util.{hpp,cpp}: the helpers the effects' evidence and vibration features share
// (binned means, Pearson correlation, hat basis, quantile knots, band residual in dB).

#include "../../../modeling/src/effects/effect_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

namespace hapticlab::modeling::wb::effect_util_test {
namespace {
using namespace detail;

TEST(EffectUtil, BinMeansUseHalfOpenBinsAndOnlyTheSelectedItems) {
  const std::vector<double> key = {0.0, 0.5, 0.999, 1.0, 1.5, 2.0, 2.5, 7};
  const std::vector<double> val = {1, 2, 3, 10, 20, 100, 200, 1000};
  const auto b = BinMeans(
      key.size(), [&](std::size_t i) { return val[i]; }, [&](std::size_t i) { return key[i]; },
      [&](std::size_t i) { return i != 1; }, {0, 1, 2, 3});
  ASSERT_EQ(b.mean.size(), 3u);
  EXPECT_EQ(b.n[0], 2);  // 0.0 and 0.999 (0.5 not selected)
  EXPECT_DOUBLE_EQ(b.mean[0], 2.0);
  EXPECT_EQ(b.n[1], 2);  // 1.0 and 1.5: the lower edge belongs to the bin
  EXPECT_DOUBLE_EQ(b.mean[1], 15.0);
  EXPECT_EQ(b.n[2], 2);  // 2.0, 2.5; 7 is outside every bin
  EXPECT_DOUBLE_EQ(b.mean[2], 150.0);
  EXPECT_EQ(b.lo[1], 1);
  EXPECT_EQ(b.hi[1], 2);
  // Populated bins only (min_n items), ties and empties.
  EXPECT_EQ(b.ArgMax(2), 2);
  EXPECT_EQ(b.ArgMin(2), 0);
  EXPECT_EQ(b.ArgMax(3), -1);
  EXPECT_EQ(b.First(2), 0);
  EXPECT_EQ(b.Last(2), 2);
  Bins gaps;
  gaps.mean = {5, -1, 7, 3};
  gaps.n = {1, 30, 0, 25};
  EXPECT_EQ(gaps.First(), 1);
  EXPECT_EQ(gaps.Last(), 3);
  EXPECT_EQ(gaps.ArgMax(), 3);
  EXPECT_EQ(gaps.ArgMin(), 1);
  EXPECT_EQ(gaps.First(31), -1);
  EXPECT_EQ(gaps.Last(31), -1);
}

TEST(EffectUtil, CorrelationIsPearsonsR) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0, 1);
  std::vector<double> x(500), y(500);
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i] = 1e3 + g(rng);  // a large offset: the one-pass sums must still be accurate
    y[i] = 0.6 * x[i] + g(rng);
  }
  // Two-pass reference over the selected items (every third left out).
  const auto use = [](std::size_t i) { return i % 3 != 0; };
  double mx = 0, my = 0;
  int n = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (use(i)) mx += x[i], my += y[i], ++n;
  mx /= n, my /= n;
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (use(i))
      sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx),
          syy += (y[i] - my) * (y[i] - my);
  const double r = Correlation(
      x.size(), [&](std::size_t i) { return y[i]; }, [&](std::size_t i) { return x[i]; }, use);
  EXPECT_NEAR(r, sxy / std::sqrt(sxx * syy), 1e-6);
  EXPECT_GT(r, 0.4);
  // R 4.2: x <- c(0.3, 1.7, 2.2, 3.9, 4.1, 5.8, 6.6, 7.0); y <- c(2.1, 1.4, 3.9, 3.0, 5.2, 4.4,
  // 7.9, 6.1); cor(x, y); cor(x[-c(2, 5)], y[-c(2, 5)]).
  const double xs[] = {0.3, 1.7, 2.2, 3.9, 4.1, 5.8, 6.6, 7.0};
  const double ys[] = {2.1, 1.4, 3.9, 3.0, 5.2, 4.4, 7.9, 6.1};
  const auto cor = [&](auto use_i) {
    return Correlation(
        8, [&](std::size_t i) { return ys[i]; }, [&](std::size_t i) { return xs[i]; }, use_i);
  };
  EXPECT_NEAR(cor([](std::size_t) { return true; }), 0.84315470158020434, 1e-12);
  EXPECT_NEAR(cor([](std::size_t i) { return i != 1 && i != 4; }), 0.83139511671753596, 1e-12);
  // Degenerate: fewer than three items, or a constant.
  EXPECT_EQ(Correlation(
                2, [](std::size_t i) { return static_cast<double>(i); },
                [](std::size_t i) { return 2.0 * static_cast<double>(i); },
                [](std::size_t) { return true; }),
            0);
  EXPECT_EQ(
      Correlation(
          10, [](std::size_t) { return 4.0; }, [](std::size_t i) { return static_cast<double>(i); },
          [](std::size_t) { return true; }),
      0);
}

TEST(EffectUtil, HatsArePiecewiseLinearAndSumToOne) {
  const double t[4] = {-1, 0, 0.5, 2};
  double h[4];
  for (double u = -2; u <= 3; u += 0.01) {
    Hats(t, 4, u, h);
    EXPECT_NEAR(h[0] + h[1] + h[2] + h[3], 1, 1e-12) << u;
    // They reproduce a linear function of u between the knots (clamped outside).
    const double uc = std::clamp(u, t[0], t[3]);
    EXPECT_NEAR(h[0] * t[0] + h[1] * t[1] + h[2] * t[2] + h[3] * t[3], uc, 1e-12) << u;
    for (const double x : h) EXPECT_GE(x, 0);
  }
  Hats(t, 4, 0.25, h);
  EXPECT_DOUBLE_EQ(h[1], 0.5);
  EXPECT_DOUBLE_EQ(h[2], 0.5);
}

TEST(EffectUtil, LogQuantileKnotsAreDistinctAndAscending) {
  Replay r;
  for (const double v : {0.02, 0.02, 0.02, 0.02, 0.05, 0.1}) {
    Replay::Window w{};
    w.speed_mps = v;
    w.force_N = 0;  // ln of a load floors at 1 mN
    r.windows.push_back(w);
  }
  const auto k = LogQuantileKnots(r, 4, /*speed=*/true);
  ASSERT_EQ(k.size(), 4u);
  EXPECT_DOUBLE_EQ(k[0], std::log(0.02));
  EXPECT_DOUBLE_EQ(k[3], std::log(0.1));
  for (std::size_t i = 1; i < k.size(); ++i) EXPECT_GE(k[i] - k[i - 1], 1e-3 - 1e-12) << i;
  EXPECT_NEAR(k[1], std::log(0.02) + 1e-3, 1e-12);  // a repeated quantile is nudged up
  const auto f = LogQuantileKnots(r, 3, /*speed=*/false);
  EXPECT_DOUBLE_EQ(f[0], std::log(1e-3));
  // No windows: fixed knots one e-fold apart.
  const auto none = LogQuantileKnots(Replay{}, 3, true);
  EXPECT_DOUBLE_EQ(none[0], std::log(0.01));
  EXPECT_DOUBLE_EQ(none[2], std::log(0.01) + 2);
}

TEST(EffectUtil, BandResidualIsTheMeanLogRatioInDecibels) {
  Residuals res;
  // Measured / predicted power ratios 2 and 8 in two bands: the geometric mean 4 is 6.02 dB.
  res.log_band = {{std::log(2.0), std::log(8.0)}, {}};
  EXPECT_NEAR(MeanBandResidualDb(res, 0), 10 * std::log10(4.0), 1e-12);
  EXPECT_EQ(MeanBandResidualDb(res, 1), 0);
}

TEST(EffectUtil, SlidingAndRatioResidualFollowTheRegimeThresholds) {
  Replay r;
  Replay::Sample s{};
  s.contact = true;
  s.fn_N = 2;
  s.speed_mps = kSlidingSpeed_mps;
  r.mutable_samples().push_back(s);
  s.speed_mps = 0.99 * kSlidingSpeed_mps;
  s.fn_N = 0.04;
  r.mutable_samples().push_back(s);
  s.contact = false;
  s.speed_mps = 1;
  r.mutable_samples().push_back(s);
  EXPECT_TRUE(Sliding(r, 0));
  EXPECT_FALSE(Sliding(r, 1));
  EXPECT_FALSE(Sliding(r, 2));
  Residuals res;
  res.friction_N = {0.5, 0.5, 0.5};
  EXPECT_DOUBLE_EQ(RatioResidual(r, res, 0), 0.25);
  EXPECT_EQ(RatioResidual(r, res, 1), 0) << "no ratio at loads of 0.05 N or less";
  const auto p = ModulationCoefficient("c", "doc");
  EXPECT_EQ(p.init, 0);
  EXPECT_GT(p.lo, -1) << "mu_k (1 + c) stays positive";
  EXPECT_LT(p.hi, 1);
}

}  // namespace
}  // namespace hapticlab::modeling::wb::effect_util_test
