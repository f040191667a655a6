// effects/stribeck.cpp: the Stribeck curve, friction above the Coulomb level at low sliding
// speed, f_C = f_n (mu_k + dmu_s exp(-(v / v_s)^2)) (the Gaussian form of Armstrong-Helouvry,
// Dupont and Canudas de Wit, Automatica 30(7), 1994).

#include <gtest/gtest.h>

#include <cmath>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::stribeck_test {
namespace {
using namespace effect_test;

double Stribeck(double mu_k, double dmu, double vs_mps, double v_mps) {
  return mu_k + dmu * std::exp(-(v_mps / vs_mps) * (v_mps / vs_mps));
}

TEST(StribeckEffect, FrictionFollowsTheGaussianStribeckCurve) {
  Replay r;
  const double vs = 0.008;
  for (const double v : {0.004, 0.008, 0.016, 0.04}) {
    Replay::Sample s{};
    s.vx_mps = -v, s.speed_mps = v;
    s.dir_rad = 3.141592653589793;
    s.fn_N = s.fload_N = 2;
    s.contact = true;
    r.mutable_samples().push_back(s);
  }
  Model m;
  m.effects = {std::string(effect::kCoulomb), std::string(effect::kStribeck)};
  m.Set(key::kMuK, 0.25);
  m.Set(key::kStribeckDmu, 0.2);
  m.Set(key::kStribeckSpeed_mps, vs);
  const auto p = Predict(m, r);
  for (std::size_t i = 0; i < r.samples().size(); ++i) {
    const double v = r.samples()[i].speed_mps;
    // tanh(v / 0.5 mm/s): the model's smoothing of ideal Coulomb friction near rest.
    EXPECT_NEAR(p.ftx_N[i], 2 * Stribeck(0.25, 0.2, vs, v) * std::tanh(v / 0.5e-3), 1e-9) << v;
  }
  // At v = v_s the excess has fallen to 1/e of dmu_s.
  EXPECT_NEAR(p.ftx_N[1] / 2 - 0.25, 0.2 / std::exp(1.0), 1e-6);
  // It modifies the Coulomb level, so adding it brings coulomb along.
  const auto deps = FindEffect(effect::kStribeck)->requires_effects();
  ASSERT_EQ(deps.size(), 1u);
  EXPECT_EQ(deps[0], effect::kCoulomb);
}

TEST(StribeckEffect, FitRecoversTheCurveFromSpeedSweeps) {
  const double mu_k = 0.3, dmu = 0.25, vs = 0.01;
  std::vector<Stroke> strokes;
  for (int k = 0; k < 6; ++k) {
    const double phi = k * 1.0;
    strokes.push_back({phi, 0.002, 0.06, 1.0, 2.5, 1.2});         // accelerating
    strokes.push_back({phi + 0.5, 0.05, 0.003, 2.0, 1.0, 1.0});   // decelerating
    strokes.push_back({phi + 0.2, 0.006, 0.006, 1.5, 1.5, 0.4});  // slow and steady
  }
  const auto r = MakeStrokes(
      strokes,
      [&](const Replay::Sample& s) { return s.fload_N * Stribeck(mu_k, dmu, vs, s.speed_mps); }, 0,
      0.01, 21);
  Model m = ModelOf({"stribeck"}, r);
  ASSERT_TRUE(m.Has(effect::kCoulomb));
  const auto rep = Fit(&m, r, {.normal = false, .vibration = false});
  EXPECT_TRUE(rep.IsUsable());
  EXPECT_NEAR(m.At(key::kMuK), mu_k, 0.01);
  EXPECT_NEAR(m.At(key::kStribeckDmu), dmu, 0.02);
  EXPECT_NEAR(m.At(key::kStribeckSpeed_mps), vs, 0.001);
}

TEST(StribeckEffect, EvidenceIsExcessFrictionAtLowSpeedOnly) {
  const auto strokes = StarOfStrokes(4, 0.002, 0.12);
  Model m;
  m.effects = {std::string(effect::kCoulomb)};
  m.Set(key::kMuK, 0.3);
  const auto with = MakeStrokes(
      strokes,
      [](const Replay::Sample& s) { return s.fload_N * Stribeck(0.3, 0.3, 0.008, s.speed_mps); }, 0,
      0.01, 22);
  const auto seen = EvidenceOf(effect::kStribeck, m, with);
  EXPECT_FALSE(seen.contradicts) << seen.pattern;
  EXPECT_EQ(seen.pattern.find("no excess"), std::string::npos) << seen.pattern;
  const auto without = MakeStrokes(
      strokes, [](const Replay::Sample& s) { return 0.3 * s.fload_N; }, 0, 0.01, 23);
  const auto null = EvidenceOf(effect::kStribeck, m, without);
  EXPECT_TRUE(null.contradicts) << null.pattern;
  EXPECT_NE(null.pattern.find("no excess friction at low speed"), std::string::npos);
  // Friction rising with speed (viscous) is not a Stribeck curve either.
  const auto viscous = MakeStrokes(
      strokes, [](const Replay::Sample& s) { return 0.3 * s.fload_N; }, 2.0, 0.01, 24);
  EXPECT_TRUE(EvidenceOf(effect::kStribeck, m, viscous).contradicts);
}

}  // namespace
}  // namespace hapticlab::modeling::wb::stribeck_test
