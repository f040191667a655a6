// effects/base_layer.cpp: a stiff base under a compliant layer of thickness t,
// f = K (d / 1 mm)^n + K_b max(0, d - t) (the base of dissertation eqs. 4.14-4.15): a knee in
// the force-penetration curve at d = t.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::base_layer_test {
namespace {
using namespace effect_test;

double Layered(double K, double Kb, double t, double d) {
  return K * d / 1e-3 + Kb * std::max(0.0, d - t);
}

TEST(BaseLayerEffect, ForceHasAKneeAtTheLayerThickness) {
  Model m;
  m.effects = {std::string(effect::kBaseLayer)};
  m.Set(key::kK1mm_N, 1.0);
  m.Set(key::kBaseK_N_per_m, 5000);
  m.Set(key::kLayer_m, 0.5e-3);
  Replay r;
  for (const double d : {0.1e-3, 0.5e-3, 0.6e-3, 1.2e-3}) {
    Replay::Sample s{};
    s.d_m = d;
    s.contact = true;
    r.mutable_samples().push_back(s);
  }
  const auto p = Predict(m, r);
  for (std::size_t i = 0; i < 4; ++i)
    EXPECT_NEAR(p.fn_N[i], Layered(1.0, 5000, 0.5e-3, r.samples()[i].d_m), 1e-12) << i;
  // Slope 1 N/mm above the knee, 1 + 5 N/mm below the surface of the base.
  EXPECT_NEAR((p.fn_N[1] - p.fn_N[0]) / 0.4, 1.0, 1e-9);
  EXPECT_NEAR((p.fn_N[3] - p.fn_N[2]) / 0.6, 6.0, 1e-9);
}

TEST(BaseLayerEffect, InitialThicknessIsTheSixtiethPercentileOfDepth) {
  Replay r;
  for (int k = 0; k < 100; ++k) {
    Replay::Sample s{};
    s.d_m = (k % 10) * 0.1e-3 + (k / 10) * 1e-6;  // 0 .. 0.909 mm
    s.contact = k % 7 != 0;
    r.mutable_samples().push_back(s);
  }
  std::vector<double> d;
  for (const auto& s : r.samples())
    if (s.contact) d.push_back(s.d_m);
  std::sort(d.begin(), d.end());
  const auto spec = FindEffect(effect::kBaseLayer)->Params(r);
  ASSERT_EQ(spec.size(), 2u);
  EXPECT_EQ(spec[1].name, key::kLayer_m.name);
  EXPECT_EQ(spec[1].init, d[static_cast<std::size_t>(0.6 * static_cast<double>(d.size()))]);
}

TEST(BaseLayerEffect, FitRecoversTheKneeFromPresses) {
  const auto r =
      MakePresses([](double d, double) { return Layered(1.2, 4000, 0.6e-3, d); }, 0.01, 91);
  Model m = ModelOf({"base-layer"}, r);
  const auto rep = Fit(&m, r, {.friction = false, .vibration = false});
  EXPECT_TRUE(rep.IsUsable());
  EXPECT_NEAR(m.At(key::kK1mm_N), 1.2, 0.02);
  EXPECT_NEAR(m.At(key::kBaseK_N_per_m), 4000, 100);
  EXPECT_NEAR(m.At(key::kLayer_m), 0.6e-3, 0.01e-3);
}

TEST(BaseLayerEffect, EvidenceIsExcessForceAtTheDeepestPenetration) {
  const auto knee =
      MakePresses([](double d, double) { return Layered(1.2, 6000, 0.7e-3, d); }, 0.01, 92);
  Model spring;
  spring.Set(key::kK1mm_N, 1.2);
  const auto seen = EvidenceOf(effect::kBaseLayer, spring, knee);
  EXPECT_FALSE(seen.contradicts) << seen.pattern;
  const auto plain =
      MakePresses([](double d, double) { return Layered(1.2, 0, 0.7e-3, d); }, 0.01, 93);
  const auto null = EvidenceOf(effect::kBaseLayer, spring, plain);
  EXPECT_TRUE(null.contradicts) << null.pattern;
}

}  // namespace
}  // namespace hapticlab::modeling::wb::base_layer_test
