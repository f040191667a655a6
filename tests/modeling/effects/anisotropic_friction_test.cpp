// effects/anisotropic_friction.cpp: the friction coefficient as a Fourier series in the
// direction of motion phi, mu(phi) = mu_k (1 + a1 cos phi + b1 sin phi + a2 cos 2phi + b2 sin
// 2phi).

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::anisotropic_friction_test {
namespace {
using namespace effect_test;

constexpr double kPi = 3.141592653589793;

double Mu(double mu_k, const double (&h)[4], double phi) {
  return mu_k * (1 + h[0] * std::cos(phi) + h[1] * std::sin(phi) + h[2] * std::cos(2 * phi) +
                 h[3] * std::sin(2 * phi));
}

Model Aniso(double mu_k, const double (&h)[4]) {
  Model m;
  m.effects = {std::string(effect::kCoulomb), std::string(effect::kAnisotropicFriction)};
  m.Set(key::kMuK, mu_k);
  for (int k = 0; k < 4; ++k) m.Set(key::kAnisotropy[k], h[k]);
  return m;
}

TEST(AnisotropicFrictionEffect, CoefficientFollowsTheDirectionalFourierSeries) {
  const double h[4] = {0.1, -0.05, 0.3, 0.08};
  Replay r;
  for (int k = 0; k < 16; ++k) {
    const double phi = -kPi + (k + 0.25) * kPi / 8;
    Replay::Sample s{};
    s.vx_mps = 0.05 * std::cos(phi), s.vy_mps = 0.05 * std::sin(phi), s.speed_mps = 0.05;
    s.dir_rad = phi;
    s.fn_N = s.fload_N = 1;
    s.contact = true;
    r.mutable_samples().push_back(s);
  }
  const auto p = Predict(Aniso(0.4, h), r);
  for (std::size_t i = 0; i < r.samples().size(); ++i)
    EXPECT_NEAR(std::hypot(p.ftx_N[i], p.fty_N[i]), Mu(0.4, h, r.samples()[i].dir_rad), 1e-9)
        << r.samples()[i].dir_rad;
  // Grain along x (a2 > 0): stroking along x and back meets more friction than across.
  const double along = std::hypot(p.ftx_N[7], p.fty_N[7]);     // phi near 0
  const double across = std::hypot(p.ftx_N[11], p.fty_N[11]);  // phi near pi/2
  EXPECT_GT(along, across);
  // The four coefficients start neutral and stay within +-0.9 so mu stays positive.
  const auto spec = FindEffect(effect::kAnisotropicFriction)->Params(r);
  ASSERT_EQ(spec.size(), 4u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(spec[k].name, key::kAnisotropy[k].name);
    EXPECT_EQ(spec[k].init, 0);
    EXPECT_EQ(spec[k].lo, -0.9);
    EXPECT_EQ(spec[k].hi, 0.9);
  }
}

TEST(AnisotropicFrictionEffect, FitRecoversTheHarmonicsFromStrokesInTwelveDirections) {
  const double h[4] = {0.12, 0.0, 0.25, -0.1};
  const auto r = MakeStrokes(
      StarOfStrokes(12),
      [&](const Replay::Sample& s) { return s.fload_N * Mu(0.35, h, s.dir_rad); }, 0, 0.01, 31);
  Model m = ModelOf({"anisotropic-friction"}, r);
  const auto rep = Fit(&m, r, {.normal = false, .vibration = false});
  EXPECT_TRUE(rep.IsUsable());
  EXPECT_NEAR(m.At(key::kMuK), 0.35, 0.005);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(m.At(key::kAnisotropy[k]), h[k], 0.015) << k;
}

TEST(AnisotropicFrictionEffect, EvidenceNamesTheDirectionsAndIsAbsentOnIsotropicFriction) {
  const double h[4] = {0, 0, 0.3, 0};
  const Model iso = Aniso(0.35, {0, 0, 0, 0});
  const auto with = MakeStrokes(
      StarOfStrokes(8), [&](const Replay::Sample& s) { return s.fload_N * Mu(0.35, h, s.dir_rad); },
      0, 0.01, 32);
  const auto seen = EvidenceOf(effect::kAnisotropicFriction, iso, with);
  EXPECT_FALSE(seen.contradicts) << seen.pattern;
  // Most friction along +-x (the bins centred on +-22.5 or +-157.5 deg), none along +-y.
  const auto at = seen.pattern.rfind("(toward ");
  ASSERT_NE(at, std::string::npos) << seen.pattern;
  const double hi_deg = std::abs(std::stod(seen.pattern.substr(at + 8)));
  EXPECT_TRUE(std::abs(hi_deg - 22.5) < 1 || std::abs(hi_deg - 157.5) < 1) << seen.pattern;
  const auto isotropic = MakeStrokes(
      StarOfStrokes(8), [](const Replay::Sample& s) { return 0.35 * s.fload_N; }, 0, 0.01, 33);
  const auto null = EvidenceOf(effect::kAnisotropicFriction, iso, isotropic);
  EXPECT_TRUE(null.contradicts) << null.pattern;
}

}  // namespace
}  // namespace hapticlab::modeling::wb::anisotropic_friction_test
