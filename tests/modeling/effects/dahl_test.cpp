// effects/dahl.cpp: Dahl's pre-sliding friction (dissertation eq. 4.6), dF/dx = kappa (1 - F/f_C
// sgn(dx)): from rest, F(x) = f_C (1 - exp(-kappa x / f_C)); after a reversal at F_0,
// F(x') = -f_C + (F_0 + f_C) exp(-kappa x' / f_C) (P. R. Dahl, "Solid friction damping of
// mechanical vibrations", AIAA J. 14(12), 1976).

#include <gtest/gtest.h>

#include <cmath>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::dahl_test {
namespace {
using namespace effect_test;

Model DahlModel(double mu_k, double kappa_N_per_m) {
  Model m;
  m.effects = {std::string(effect::kCoulomb), std::string(effect::kDahl)};
  m.Set(key::kMuK, mu_k);
  m.Set(key::kKappa_N_per_m, kappa_N_per_m);
  return m;
}

// Samples along direction phi at arc positions s_m[k] (the velocity from the steps).
Replay Path(const std::vector<double>& s_m, double phi, double load_N) {
  Replay r;
  r.position_resolution_m = 0;  // no play: Dahl's law as written
  for (std::size_t k = 0; k < s_m.size(); ++k) {
    Replay::Sample s{};
    s.t_s = static_cast<double>(k) / kRate_hz;
    s.x_m = s_m[k] * std::cos(phi), s.y_m = s_m[k] * std::sin(phi);
    const double v = k ? (s_m[k] - s_m[k - 1]) * kRate_hz : (s_m[1] - s_m[0]) * kRate_hz;
    s.vx_mps = v * std::cos(phi), s.vy_mps = v * std::sin(phi), s.speed_mps = std::abs(v);
    s.dir_rad = std::atan2(s.vy_mps, s.vx_mps);
    s.fn_N = s.fload_N = load_N;
    s.contact = true;
    r.mutable_samples().push_back(s);
  }
  return r;
}

TEST(DahlEffect, FrictionBuildsUpAndReversesAlongDahlsExponential) {
  const double mu_k = 0.4, kappa = 2500, load = 1.5, fc = mu_k * load;  // f_C / kappa = 0.24 mm
  std::vector<double> s;
  for (int k = 0; k <= 100; ++k) s.push_back(k * 10e-6);        // 1 mm forward, 10 um steps
  for (int k = 1; k <= 60; ++k) s.push_back(1e-3 - k * 10e-6);  // 0.6 mm back
  const double phi = 0.7;
  const auto r = Path(s, phi, load);
  const auto p = Predict(DahlModel(mu_k, kappa), r);
  const double F0 = fc * (1 - std::exp(-kappa * 1e-3 / fc));  // at the reversal
  for (std::size_t k = 0; k < s.size(); ++k) {
    // Force on the tool along the +phi axis: minus the bristle force.
    const double along = p.ftx_N[k] * std::cos(phi) + p.fty_N[k] * std::sin(phi);
    const double across = -p.ftx_N[k] * std::sin(phi) + p.fty_N[k] * std::cos(phi);
    double bristle = 0;
    if (k <= 100) {
      bristle = fc * (1 - std::exp(-kappa * s[k] / fc));
    } else {
      const double back = 1e-3 - s[k];
      bristle = -fc + (F0 + fc) * std::exp(-kappa * back / fc);
    }
    EXPECT_NEAR(along, -bristle, 1e-9) << k;
    EXPECT_NEAR(across, 0, 1e-12) << k;
  }
  // Saturation: never beyond the Coulomb level.
  EXPECT_LT(F0, fc);
  EXPECT_GT(F0, 0.98 * fc);
}

TEST(DahlEffect, PositionNoiseInsideThePlayDoesNotMoveTheBristle) {
  std::vector<double> s = {0, 0.1e-3, 0.2e-3};
  // Forward motion leaves the bristle one half-play (1 um) behind the tool; jitter around there.
  for (int k = 0; k < 20; ++k) s.push_back(0.2e-3 - 1e-6 + (k % 2 ? 0.4e-6 : -0.4e-6));
  auto r = Path(s, 0, 1);
  r.position_resolution_m = 2e-6;  // a play of +-1 um
  const auto p = Predict(DahlModel(0.5, 4000), r);
  for (std::size_t k = 4; k < s.size(); ++k) EXPECT_EQ(p.ftx_N[k], p.ftx_N[3]) << k;
}

// Back-and-forth strokes along several directions, x(t) = A sin(2 pi t / T), with the friction
// of a Dahl bristle integrated here by explicit Euler in 50 sub-steps per sample (dahl) or
// Coulomb friction smoothed as the workbench documents it, f_C tanh(v / 0.5 mm/s) (no dahl).
Replay Oscillations(bool dahl, double fc_N, double kappa, double noise_N, unsigned seed) {
  Replay r;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, noise_N);
  double t_s = 0;
  int cycle = 0;
  for (const double A : {0.3e-3, 0.8e-3, 2e-3})
    for (const double T : {1.0, 0.5}) {
      const double phi = 0.9 * cycle++, w = 2 * 3.141592653589793 / T;
      double F = 0;  // bristle force along +phi
      const int n = static_cast<int>(2 * T * kRate_hz);
      for (int k = 0; k < n; ++k) {
        const double tau = k / kRate_hz, x = A * std::sin(w * tau), v = A * w * std::cos(w * tau);
        if (k > 0)
          for (int j = 0; j < 50; ++j) {
            const double dx = A * (std::sin(w * (tau - (49 - j) / (50 * kRate_hz))) -
                                   std::sin(w * (tau - (50 - j) / (50 * kRate_hz))));
            F += kappa * (dx - std::abs(dx) * F / fc_N);
          }
        const double bristle = dahl ? F : fc_N * std::tanh(v / 0.5e-3);
        Replay::Sample s{};
        s.x_m = x * std::cos(phi), s.y_m = x * std::sin(phi);
        s.vx_mps = v * std::cos(phi), s.vy_mps = v * std::sin(phi), s.speed_mps = std::abs(v);
        s.dir_rad = std::atan2(s.vy_mps, s.vx_mps);
        s.fn_N = s.fload_N = 1.5;
        s.ftx_N = -bristle * std::cos(phi) + noise(rng);
        s.fty_N = -bristle * std::sin(phi) + noise(rng);
        Append(&r, s, true, &t_s);
      }
      LiftOff(&r, &t_s);
    }
  Finish(&r);
  return r;
}

TEST(DahlEffect, FitRecoversKappaFromReversals) {
  const double mu_k = 0.3, kappa = 3000;
  const auto r = Oscillations(true, mu_k * 1.5, kappa, 0.005, 61);
  Model m = ModelOf({"dahl"}, r);
  ASSERT_TRUE(m.Has(effect::kCoulomb)) << "dahl modifies the Coulomb level";
  const auto rep = Fit(&m, r, {.normal = false, .vibration = false});
  EXPECT_TRUE(rep.IsUsable());
  EXPECT_NEAR(m.At(key::kMuK), mu_k, 0.005);
  EXPECT_NEAR(m.At(key::kKappa_N_per_m), kappa, 0.05 * kappa);
}

TEST(DahlEffect, EvidenceIsResidualConcentratedAtStartsAndReversals) {
  Model coulomb;
  coulomb.effects = {std::string(effect::kCoulomb)};
  coulomb.Set(key::kMuK, 0.3);
  const auto with = Oscillations(true, 0.45, 1500, 0.005, 62);
  const auto seen = EvidenceOf(effect::kDahl, coulomb, with);
  EXPECT_FALSE(seen.contradicts) << seen.pattern;
  const auto without = Oscillations(false, 0.45, 0, 0.005, 63);
  const auto null = EvidenceOf(effect::kDahl, coulomb, without);
  EXPECT_TRUE(null.contradicts) << null.pattern;
}

}  // namespace
}  // namespace hapticlab::modeling::wb::dahl_test
