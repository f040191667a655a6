// effects/load_dependent_friction.cpp: friction growing as a power of the load,
// f_C = mu_k f_n (f_n / 1 N)^(alpha - 1) = mu_k f_n^alpha (alpha = 2/3 for adhesive friction on a
// Hertzian contact, whose area grows as f_n^(2/3): Bowden and Tabor; Johnson, Contact
// Mechanics, 1985, ch. 4).

#include <gtest/gtest.h>

#include <cmath>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::load_dependent_friction_test {
namespace {
using namespace effect_test;

TEST(LoadDependentFrictionEffect, FrictionIsMuKTimesTheLoadToThePowerAlpha) {
  Replay r;
  for (const double f : {0.25, 1.0, 4.0}) {
    Replay::Sample s{};
    s.vy_mps = s.speed_mps = 0.04;
    s.dir_rad = 3.141592653589793 / 2;
    s.fn_N = s.fload_N = f;
    s.contact = true;
    r.mutable_samples().push_back(s);
  }
  Model m;
  m.effects = {std::string(effect::kCoulomb), std::string(effect::kLoadDependentFriction)};
  m.Set(key::kMuK, 0.5);
  m.Set(key::kLoadAlpha, 2.0 / 3);
  const auto p = Predict(m, r);
  for (std::size_t i = 0; i < 3; ++i) {
    const double f = r.samples()[i].fload_N;
    EXPECT_NEAR(-p.fty_N[i], 0.5 * std::pow(f, 2.0 / 3), 1e-9) << f;
    EXPECT_NEAR(p.ftx_N[i], 0, 1e-12);
  }
  // At 1 N the law is Coulomb's; the coefficient halves for each 8-fold increase in load.
  EXPECT_NEAR(-p.fty_N[1], 0.5, 1e-12);
  const auto spec = FindEffect(effect::kLoadDependentFriction)->Params(r);
  ASSERT_EQ(spec.size(), 1u);
  EXPECT_EQ(spec[0].init, 1.0) << "starts as Coulomb friction";
}

TEST(LoadDependentFrictionEffect, FitRecoversAlphaFromLoadSweeps) {
  const double mu_k = 0.4, alpha = 0.7;
  std::vector<Stroke> strokes;
  for (int k = 0; k < 8; ++k) {
    strokes.push_back({k * 0.8, 0.04, 0.04, 0.2, 4.0, 1.0});
    strokes.push_back({k * 0.8 + 0.4, 0.08, 0.02, 3.0, 0.3, 0.6});
  }
  const auto r = MakeStrokes(
      strokes, [&](const Replay::Sample& s) { return mu_k * std::pow(s.fload_N, alpha); }, 0, 0.01,
      41);
  Model m = ModelOf({"load-dependent-friction"}, r);
  const auto rep = Fit(&m, r, {.normal = false, .vibration = false});
  EXPECT_TRUE(rep.IsUsable());
  EXPECT_NEAR(m.At(key::kLoadAlpha), alpha, 0.01);
  EXPECT_NEAR(m.At(key::kMuK), mu_k, 0.005);
}

TEST(LoadDependentFrictionEffect, EvidenceIsARatioResidualThatChangesWithLoad) {
  const auto strokes = StarOfStrokes(6);
  Model coulomb;
  coulomb.effects = {std::string(effect::kCoulomb)};
  coulomb.Set(key::kMuK, 0.4);
  const auto soft = MakeStrokes(
      strokes, [](const Replay::Sample& s) { return 0.4 * std::pow(s.fload_N, 0.6); }, 0, 0.01, 42);
  const auto seen = EvidenceOf(effect::kLoadDependentFriction, coulomb, soft);
  EXPECT_FALSE(seen.contradicts) << seen.pattern;
  EXPECT_EQ(seen.cause, "the friction coefficient falls with load");
  const auto hard = MakeStrokes(
      strokes, [](const Replay::Sample& s) { return 0.4 * std::pow(s.fload_N, 1.3); }, 0, 0.01, 43);
  EXPECT_EQ(EvidenceOf(effect::kLoadDependentFriction, coulomb, hard).cause,
            "the friction coefficient rises with load");
  const auto plain = MakeStrokes(
      strokes, [](const Replay::Sample& s) { return 0.4 * s.fload_N; }, 0, 0.01, 44);
  const auto null = EvidenceOf(effect::kLoadDependentFriction, coulomb, plain);
  EXPECT_TRUE(null.contradicts) << null.pattern;
  // One load only: nothing to compare.
  const auto one_load = MakeStrokes({{0, 0.05, 0.05, 1.2, 1.2, 1}},
                                    [](const Replay::Sample& s) { return 0.4 * s.fload_N; });
  EXPECT_EQ(EvidenceOf(effect::kLoadDependentFriction, coulomb, one_load).pattern,
            "too narrow a range of loads to judge");
}

}  // namespace
}  // namespace hapticlab::modeling::wb::load_dependent_friction_test
