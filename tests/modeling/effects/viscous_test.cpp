// effects/viscous.cpp: viscous friction, a tangential force mu_b v proportional to the sliding
// velocity on top of Coulomb's (the mu_b term of dissertation eq. 4.7).

#include <gtest/gtest.h>

#include <cmath>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::viscous_test {
namespace {
using namespace effect_test;

TEST(ViscousEffect, AddsMuBTimesTheVelocityToCoulombFriction) {
  Replay r;
  for (const double phi : {0.3, -1.2, 2.9})
    for (const double v : {0.01, 0.05, 0.2}) {
      Replay::Sample s{};
      s.vx_mps = v * std::cos(phi), s.vy_mps = v * std::sin(phi), s.speed_mps = v;
      s.dir_rad = phi;
      s.fn_N = s.fload_N = 1.5;
      s.contact = true;
      r.mutable_samples().push_back(s);
    }
  Model m;
  m.effects = {std::string(effect::kCoulomb), std::string(effect::kViscous)};
  m.Set(key::kMuK, 0.3);
  m.Set(key::kMuB_Ns_per_m, 2.0);
  const auto p = Predict(m, r);
  for (std::size_t i = 0; i < r.samples().size(); ++i) {
    const auto& s = r.samples()[i];
    // f_t = -(mu_k f_n + mu_b |v|) v / |v|.
    const double mag = 0.3 * 1.5 + 2.0 * s.speed_mps;
    EXPECT_NEAR(p.ftx_N[i], -mag * s.vx_mps / s.speed_mps, 1e-9) << i;
    EXPECT_NEAR(p.fty_N[i], -mag * s.vy_mps / s.speed_mps, 1e-9) << i;
  }
  const auto spec = FindEffect(effect::kViscous)->Params(r);
  ASSERT_EQ(spec.size(), 1u);
  EXPECT_EQ(spec[0].name, key::kMuB_Ns_per_m.name);
  EXPECT_EQ(spec[0].init, 0) << "neutral: no viscous friction until fitted";
  EXPECT_EQ(spec[0].lo, 0) << "a negative mu_b would feed energy into the hand";
}

TEST(ViscousEffect, FitRecoversMuBFromConstantAndSweepingSpeeds) {
  const double mu_k = 0.3, mu_b = 1.5;
  const auto r = MakeStrokes(
      StarOfStrokes(6, 0.01, 0.15), [&](const Replay::Sample& s) { return mu_k * s.fload_N; }, mu_b,
      0.01, 11);
  Model m = ModelOf({"coulomb", "viscous"}, r);
  const auto rep = Fit(&m, r, {.normal = false, .vibration = false});
  EXPECT_TRUE(rep.IsUsable());
  EXPECT_NEAR(m.At(key::kMuB_Ns_per_m), mu_b, 0.05);
  EXPECT_NEAR(m.At(key::kMuK), mu_k, 0.005);
}

TEST(ViscousEffect, EvidenceIsFrictionRisingWithSpeedAndNotFrictionFallingWithIt) {
  const auto strokes = StarOfStrokes(4, 0.005, 0.15);
  const auto coulomb = [](const Replay::Sample& s) { return 0.3 * s.fload_N; };
  Model m;
  m.effects = {std::string(effect::kCoulomb)};
  m.Set(key::kMuK, 0.3);
  const auto rising = MakeStrokes(strokes, coulomb, 1.0, 0.01, 12);
  const auto seen = EvidenceOf(effect::kViscous, m, rising);
  EXPECT_FALSE(seen.contradicts) << seen.pattern;
  EXPECT_NE(seen.pattern.find("correlation with speed +0.9"), std::string::npos) << seen.pattern;
  // Friction falling with speed (a Stribeck curve) is not viscous friction.
  const auto falling = MakeStrokes(
      strokes,
      [](const Replay::Sample& s) {
        return s.fload_N * (0.3 + 0.2 * std::exp(-std::pow(s.speed_mps / 0.02, 2)));
      },
      0, 0.01, 13);
  const auto wrong = EvidenceOf(effect::kViscous, m, falling);
  EXPECT_TRUE(wrong.contradicts) << wrong.pattern;
  // Exactly explained data leaves no pattern.
  const auto exact = MakeStrokes(strokes, coulomb, 0, 0, 14);
  EXPECT_TRUE(EvidenceOf(effect::kViscous, m, exact).contradicts);
}

}  // namespace
}  // namespace hapticlab::modeling::wb::viscous_test
