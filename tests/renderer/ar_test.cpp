#include "hapticlab/renderer/ar.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "hapticlab/core/status.hpp"
#include "hapticlab/renderer/vibration.hpp"
#include "spectrum_util.hpp"

namespace hapticlab::renderer::ar_test {
namespace {

// A random stable AR(p): poles drawn inside a disc of radius 0.95, as conjugate pairs.
std::vector<double> RandomStableAr(int p, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> rad(0.1, 0.95), ang(0.05, 3.1);
  std::vector<std::complex<double>> poly{1.0};  // A(z) in z^-1
  auto mul = [&](std::complex<double> root) {
    std::vector<std::complex<double>> next(poly.size() + 1);
    for (std::size_t i = 0; i < poly.size(); ++i) {
      next[i] += poly[i];
      next[i + 1] -= root * poly[i];
    }
    poly = next;
  };
  int k = 0;
  for (; k + 1 < p; k += 2) {
    const auto r = std::polar(rad(rng), ang(rng));
    mul(r);
    mul(std::conj(r));
  }
  if (k < p) mul(rad(rng) * (ang(rng) < 1.5 ? 1.0 : -1.0));
  std::vector<double> c(static_cast<std::size_t>(p));
  for (int i = 0; i < p; ++i)
    c[static_cast<std::size_t>(i)] = -poly[static_cast<std::size_t>(i + 1)].real();
  return c;
}

TEST(Ar, LsfRoundTripForOddAndEvenOrders) {
  std::mt19937_64 rng(7);
  for (int p = 1; p <= 30; ++p) {
    for (int trial = 0; trial < 3; ++trial) {
      const auto c = RandomStableAr(p, rng);
      ASSERT_TRUE(IsStableAr(c)) << p;
      const auto lsf = ArToLsf(c);
      ASSERT_EQ(lsf.size(), c.size());
      for (std::size_t i = 1; i < lsf.size(); ++i) EXPECT_LT(lsf[i - 1], lsf[i]);
      EXPECT_GT(lsf.front(), 0.0);
      EXPECT_LT(lsf.back(), std::numbers::pi);
      const auto back = LsfToAr(lsf);
      for (std::size_t i = 0; i < c.size(); ++i) EXPECT_NEAR(back[i], c[i], 1e-8) << "p=" << p;
    }
  }
}

TEST(Ar, UnstableFiltersAreDetected) {
  EXPECT_FALSE(IsStableAr(std::vector<double>{1.01}));       // pole at 1.01
  EXPECT_FALSE(IsStableAr(std::vector<double>{2.0, -1.0}));  // double pole at 1
  EXPECT_TRUE(IsStableAr(std::vector<double>{0.5, -0.2}));
  EXPECT_THROW(ArToLsf(std::vector<double>{1.5}), PreconditionError);
}

TEST(Ar, AnyConvexMixOfLsfsIsStable) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  for (int t = 0; t < 200; ++t) {
    const auto a = ArToLsf(RandomStableAr(16, rng));
    const auto b = ArToLsf(RandomStableAr(16, rng));
    const double w = u(rng);
    std::vector<double> mix(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) mix[i] = w * a[i] + (1 - w) * b[i];
    EXPECT_TRUE(IsStableAr(LsfToAr(mix)));
  }
}

TEST(Ar, ImpulseResponseMatchesClosedForm) {
  // AR(2) with poles r e^{±jθ}: h[k] = r^k sin((k+1)θ) / sin θ.
  const double r = 0.9, th = 0.7;
  ArFilter f;
  f.order = 2;
  f.c[0] = 2 * r * std::cos(th);
  f.c[1] = -r * r;
  f.active = true;
  ArSynth s;
  for (int k = 0; k < 60; ++k) {
    const double h = s.StepWith(f, k == 0 ? 1.0 : 0.0);
    EXPECT_NEAR(h, std::pow(r, k) * std::sin((k + 1) * th) / std::sin(th), 1e-12) << k;
  }
  // ARMA: B(z) = 1 + 0.5 z^-1 adds 0.5 h[k-1].
  f.ma_order = 1;
  f.b[0] = 0.5;
  f.gain = 2.0;
  s.Reset();
  double prev = 0;
  for (int k = 0; k < 30; ++k) {
    const double hk = std::pow(r, k) * std::sin((k + 1) * th) / std::sin(th);
    EXPECT_NEAR(s.StepWith(f, k == 0 ? 1.0 : 0.0), 2.0 * (hk + 0.5 * prev), 1e-12) << k;
    prev = hk;
  }
}

TEST(Ar, SynthesisRecursionIsTheArModel) {
  // With the noise replaced by its own draws, ArSynth's output obeys a[k] - sum c a[k-i] = x[k]
  // where x has the requested standard deviation.
  ArFilter f;
  f.order = 3;
  f.c[0] = 0.5;
  f.c[1] = -0.3;
  f.c[2] = 0.1;
  f.sigma = 2.0;
  f.active = true;
  ArSynth s(42);
  std::vector<double> a;
  for (int k = 0; k < 200000; ++k) a.push_back(s.Step(f));
  double sum2 = 0;
  for (std::size_t k = 3; k < a.size(); ++k) {
    const double e = a[k] - 0.5 * a[k - 1] + 0.3 * a[k - 2] - 0.1 * a[k - 3];
    sum2 += e * e;
  }
  const double sd = std::sqrt(sum2 / static_cast<double>(a.size() - 3));
  EXPECT_NEAR(sd, 2.0, 0.02);  // 200k draws: relative SE of the SD is ~0.16 %
}

TEST(Ar, SynthesizedSpectrumMatchesAnalyticPsd) {
  // A 10 s synthesis of a known AR(8) at 2 kHz against its analytic spectrum: E_s < 0.1.
  std::mt19937_64 rng(3);
  const auto c = RandomStableAr(8, rng);
  const double fs = 2000, var = 0.7;
  ArFilter f;
  f.order = 8;
  for (int i = 0; i < 8; ++i) f.c[static_cast<std::size_t>(i)] = c[static_cast<std::size_t>(i)];
  f.sigma = std::sqrt(var);
  f.active = true;
  ArSynth s(99);
  std::vector<double> x(20000);
  for (auto& v : x) v = s.Step(f);
  const auto est = test::WelchPsd(x, fs, 256);
  std::vector<double> ref;
  for (std::size_t k = 0; k < est.size(); ++k)
    ref.push_back(ArPsd(c, var, fs, fs * static_cast<double>(k) / 256.0));
  const double es = test::RelativeSpectralRms(est, ref);
  EXPECT_LT(es, 0.1) << "E_s = " << es;
  // And the estimate fails for a different model (the check has teeth).
  std::vector<double> other;
  const auto c2 = RandomStableAr(8, rng);
  for (std::size_t k = 0; k < est.size(); ++k)
    other.push_back(ArPsd(c2, var, fs, fs * static_cast<double>(k) / 256.0));
  EXPECT_GT(test::RelativeSpectralRms(est, other), 0.1);
}

}  // namespace
}  // namespace hapticlab::renderer::ar_test
