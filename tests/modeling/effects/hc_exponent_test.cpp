// effects/hc_exponent.cpp: the Hunt-Crossley exponent, f = K (d / 1 mm)^n (dissertation eq. 4.11;
// n = 3/2 is Hertz's sphere on an elastic half-space, F = 4/3 E* sqrt(R) d^(3/2): Johnson,
// Contact Mechanics, 1985, ch. 4).

#include <gtest/gtest.h>

#include <cmath>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::hc_exponent_test {
namespace {
using namespace effect_test;

TEST(HcExponentEffect, NormalForceIsHertzianForNThreeHalves) {
  // A 2 mm radius sphere on a half-space of E* = 0.5 MPa: F = 4/3 E* sqrt(R) d^1.5, so the force
  // at 1 mm is K1mm = 4/3 E* sqrt(R) (1 mm)^1.5.
  const double E_Pa = 0.5e6, R_m = 2e-3, c = 4.0 / 3 * E_Pa * std::sqrt(R_m);
  Model m;
  m.effects = {std::string(effect::kHcExponent)};
  m.Set(key::kK1mm_N, c * std::pow(1e-3, 1.5));
  m.Set(key::kN, 1.5);
  Replay r;
  for (const double d : {0.05e-3, 0.3e-3, 1e-3, 1.7e-3}) {
    Replay::Sample s{};
    s.d_m = d;
    s.contact = true;
    r.mutable_samples().push_back(s);
  }
  Replay::Sample air{};
  air.d_m = 1e-3;  // out of contact: no force whatever the depth says
  r.mutable_samples().push_back(air);
  const auto p = Predict(m, r);
  for (std::size_t i = 0; i < 4; ++i)
    EXPECT_NEAR(p.fn_N[i], c * std::pow(r.samples()[i].d_m, 1.5), 1e-9) << i;
  EXPECT_EQ(p.fn_N[4], 0);
  const auto spec = FindEffect(effect::kHcExponent)->Params(r);
  ASSERT_EQ(spec.size(), 1u);
  EXPECT_EQ(spec[0].lo, 1);
  EXPECT_EQ(spec[0].hi, 2);
}

TEST(HcExponentEffect, FitRecoversKAndNFromPresses) {
  const auto r =
      MakePresses([](double d, double) { return 1.8 * std::pow(d / 1e-3, 1.6); }, 0.01, 71);
  Model m = ModelOf({"hc-exponent"}, r);
  const auto rep = Fit(&m, r, {.friction = false, .vibration = false});
  EXPECT_TRUE(rep.IsUsable());
  EXPECT_NEAR(m.At(key::kN), 1.6, 0.01);
  EXPECT_NEAR(m.At(key::kK1mm_N), 1.8, 0.01);
}

TEST(HcExponentEffect, EvidenceIsAnUpwardBendAgainstALinearSpring) {
  // A linear spring fitted to a stiffening contact over-predicts shallow and under-predicts deep.
  const auto curved =
      MakePresses([](double d, double) { return 1.5 * std::pow(d / 1e-3, 1.7); }, 0.01, 72);
  Model linear;
  Fit(&linear, curved, {.friction = false, .vibration = false});
  const auto seen = EvidenceOf(effect::kHcExponent, linear, curved);
  EXPECT_FALSE(seen.contradicts) << seen.pattern;
  const auto straight = MakePresses([](double d, double) { return 1.5 * d / 1e-3; }, 0.01, 73);
  Model fitted;
  Fit(&fitted, straight, {.friction = false, .vibration = false});
  EXPECT_NEAR(fitted.At(key::kK1mm_N), 1.5, 0.01);
  const auto null = EvidenceOf(effect::kHcExponent, fitted, straight);
  EXPECT_TRUE(null.contradicts) << null.pattern;
}

}  // namespace
}  // namespace hapticlab::modeling::wb::hc_exponent_test
