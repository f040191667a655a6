// effects/coulomb.cpp: Amontons-Coulomb kinetic friction, |f_t| = mu_k f_n opposite to the
// velocity, whatever the speed and direction (dissertation eq. 4.6's f_C).

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::coulomb_test {
namespace {
using namespace effect_test;

TEST(CoulombEffect, PredictsMuKTimesTheLoadAgainstTheMotionAtAnySpeedAndDirection) {
  Replay r;
  double t_s = 0;
  // Sliding samples (>= 20 mm/s, where the model's 0.5 mm/s smoothing is complete).
  for (const double phi : {0.0, 1.0, 2.5, -2.0})
    for (const double v : {0.02, 0.1, 0.3})
      for (const double f : {0.3, 1.0, 2.7}) {
        Replay::Sample s{};
        s.t_s = t_s += 0.002;
        s.vx_mps = v * std::cos(phi), s.vy_mps = v * std::sin(phi), s.speed_mps = v;
        s.dir_rad = phi;
        s.fn_N = s.fload_N = f;
        s.contact = true;
        r.mutable_samples().push_back(s);
      }
  Model m;
  m.effects = {std::string(effect::kCoulomb)};
  m.Set(key::kMuK, 0.42);
  const auto p = Predict(m, r);
  for (std::size_t i = 0; i < r.samples().size(); ++i) {
    const auto& s = r.samples()[i];
    // Amontons: magnitude mu_k f_n, direction -v / |v|.
    EXPECT_NEAR(std::hypot(p.ftx_N[i], p.fty_N[i]), 0.42 * s.fload_N, 1e-9 * s.fload_N) << i;
    EXPECT_NEAR(p.ftx_N[i] * s.vy_mps - p.fty_N[i] * s.vx_mps, 0, 1e-12) << i;
    EXPECT_LT(p.ftx_N[i] * s.vx_mps + p.fty_N[i] * s.vy_mps, 0) << i;
  }
}

TEST(CoulombEffect, InitialValueIsTheMedianMeasuredRatioAndTheFitRecoversMuK) {
  const double mu_k = 0.37;
  const auto r = MakeStrokes(
      StarOfStrokes(), [&](const Replay::Sample& s) { return mu_k * s.fload_N; }, 0, 0.01, 3);
  const auto spec = FindEffect(effect::kCoulomb)->Params(r);
  ASSERT_EQ(spec.size(), 1u);
  EXPECT_EQ(spec[0].name, key::kMuK.name);
  EXPECT_NEAR(spec[0].init, mu_k, 0.01) << "median |f_t| / f_n while sliding";
  // The median, not another quantile: 40 % of the sliding time at 0.2, 20 % at 0.35, 40 % at 0.5.
  const auto mixed = MakeStrokes(
      {{0, 0.05, 0.05, 1, 1, 0.4}, {1, 0.05, 0.05, 1, 1, 0.2}, {2, 0.05, 0.05, 1, 1, 0.4}},
      [](const Replay::Sample& s) { return s.dir_rad < 0.5   ? 0.2
                                           : s.dir_rad < 1.5 ? 0.35
                                                             : 0.5; });
  EXPECT_NEAR(FindEffect(effect::kCoulomb)->Params(mixed)[0].init, 0.35, 1e-9);
  Model m = ModelOf({"coulomb"}, r);
  m.Set(key::kMuK, 0.1);  // start away from the answer
  const auto rep = Fit(&m, r, {.normal = false, .vibration = false});
  ASSERT_NE(rep.Find(Channel::kFriction), nullptr);
  EXPECT_TRUE(rep.Find(Channel::kFriction)->summary.converged);
  EXPECT_NEAR(m.At(key::kMuK), mu_k, 0.003);
  // No sliding samples: the neutral start value.
  Replay still;
  EXPECT_EQ(FindEffect(effect::kCoulomb)->Params(still)[0].init, 0.3);
}

TEST(CoulombEffect, EvidenceSeesMissingFrictionAndNoneOnFrictionlessData) {
  const auto with = MakeStrokes(
      StarOfStrokes(4), [](const Replay::Sample& s) { return 0.3 * s.fload_N; }, 0, 0.01, 4);
  const Model none;  // no friction effect: the residual is the whole friction
  const auto seen = EvidenceOf(effect::kCoulomb, none, with);
  EXPECT_FALSE(seen.contradicts) << seen.pattern;
  EXPECT_NE(seen.pattern.find("while sliding"), std::string::npos) << seen.pattern;
  // The residual in the highest load bin (2-3 N) is the mean friction along the motion there.
  double sum = 0;
  int n = 0;
  for (const auto& s : with.samples())
    if (s.contact && s.fn_N >= 2 && s.fn_N < 3)
      sum += -(s.ftx_N * (s.vx_mps / s.speed_mps) + s.fty_N * (s.vy_mps / s.speed_mps)), ++n;
  ASSERT_GT(n, 100);
  EXPECT_NEAR(sum / n, 0.3 * 2.5, 0.05);
  EXPECT_NE(seen.pattern.find(fmt::format("and {:+.3f} N at 2.0-3.0 N", sum / n)),
            std::string::npos)
      << seen.pattern;
  const auto frictionless = MakeStrokes(
      StarOfStrokes(4), [](const Replay::Sample&) { return 0.0; }, 0, 0.01, 5);
  const auto null = EvidenceOf(effect::kCoulomb, none, frictionless);
  EXPECT_TRUE(null.contradicts) << null.pattern;
  Replay empty;
  EXPECT_TRUE(EvidenceOf(effect::kCoulomb, none, empty).pattern.find("too few") == 0);
}

}  // namespace
}  // namespace hapticlab::modeling::wb::coulomb_test
