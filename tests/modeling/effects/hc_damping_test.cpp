// effects/hc_damping.cpp: Hunt-Crossley damping, f = (K + B d_dot) (d / 1 mm)^n (K. H. Hunt and
// F. R. E. Crossley, J. Appl. Mech. 42(2), 1975; dissertation eq. 4.11): the damping force
// scales with depth, so it vanishes at first contact, and the press-release loop dissipates
// energy.

#include <gtest/gtest.h>

#include <cmath>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::hc_damping_test {
namespace {
using namespace effect_test;

TEST(HcDampingEffect, NormalForceIsHuntCrossleyAndTheLoopDissipates) {
  const double K = 2.0, B = 30, n = 1.3;
  const auto law = [&](double d, double ddot) {
    return std::max(0.0, std::pow(d / 1e-3, n) * (K + B * ddot));
  };
  const auto r = MakePresses(law);
  Model m;
  m.effects = {std::string(effect::kHcDamping), std::string(effect::kHcExponent)};
  m.Set(key::kK1mm_N, K);
  m.Set(key::kB1mm_Ns_per_m, B);
  m.Set(key::kN, n);
  const auto p = Predict(m, r);
  double work_J = 0;  // over the first press-release cycle: integral of f dd
  for (std::size_t i = 0; i < r.samples().size(); ++i) {
    const auto& s = r.samples()[i];
    if (!s.contact) break;
    EXPECT_NEAR(p.fn_N[i], law(s.d_m, s.ddot_mps), 1e-9) << i;
    work_J += p.fn_N[i] * s.ddot_mps / kRate_hz;
  }
  EXPECT_GT(work_J, 1e-6) << "pressing in meets more force than releasing";
  // At first contact (d = 0) there is no force jump however fast the tool moves.
  Replay touch;
  Replay::Sample s{};
  s.d_m = 0;
  s.ddot_mps = 0.5;
  s.contact = true;
  touch.mutable_samples().push_back(s);
  EXPECT_EQ(Predict(m, touch).fn_N[0], 0);
  EXPECT_EQ(FindEffect(effect::kHcDamping)->Params(touch)[0].init, 0);
}

TEST(HcDampingEffect, FitRecoversBFromPressesAtSeveralRates) {
  const auto r = MakePresses(
      [](double d, double ddot) {
        return std::max(0.0, std::pow(d / 1e-3, 1.2) * (2 + 25 * ddot));
      },
      0.01, 81);
  Model m = ModelOf({"hc-damping", "hc-exponent"}, r);
  const auto rep = Fit(&m, r, {.friction = false, .vibration = false});
  EXPECT_TRUE(rep.IsUsable());
  EXPECT_NEAR(m.At(key::kB1mm_Ns_per_m), 25, 0.5);
  EXPECT_NEAR(m.At(key::kK1mm_N), 2, 0.01);
  EXPECT_NEAR(m.At(key::kN), 1.2, 0.01);
}

TEST(HcDampingEffect, EvidenceIsAResidualCorrelatedWithThePenetrationRate) {
  const auto damped = MakePresses(
      [](double d, double ddot) { return std::max(0.0, d / 1e-3 * (2 + 40 * ddot)); }, 0.01, 82);
  Model spring;
  spring.Set(key::kK1mm_N, 2);
  const auto seen = EvidenceOf(effect::kHcDamping, spring, damped);
  EXPECT_FALSE(seen.contradicts) << seen.pattern;
  const auto elastic = MakePresses([](double d, double) { return 2 * d / 1e-3; }, 0.01, 83);
  const auto null = EvidenceOf(effect::kHcDamping, spring, elastic);
  EXPECT_TRUE(null.contradicts) << null.pattern;
}

}  // namespace
}  // namespace hapticlab::modeling::wb::hc_damping_test
