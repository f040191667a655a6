// effects/vibration_axis.cpp: vibration-speed and vibration-force, the two axes of the
// dissertation's AR bank (ch. III): each band's ln power as a piecewise-linear function of
// ln(speed) or ln(load), hat features on knots at quantiles of the measured key.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <regex>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::vibration_axis_test {
namespace {
using namespace effect_test;

// Moved from workbench_model_test.cpp: the speed and force axes share one implementation: hat
// features of ln(speed) or ln(load) that sum to one with the intercept's partner column left out.
TEST(VibrationAxisEffect, VibrationAxesUseTheirOwnKeyAndKnots) {
  const Effect* sp = FindEffect("vibration-speed");
  const Effect* fo = FindEffect("vibration-force");
  ASSERT_NE(sp, nullptr);
  ASSERT_NE(fo, nullptr);
  EXPECT_EQ(sp->VibrationColumns(), 4);
  EXPECT_EQ(fo->VibrationColumns(), 2);
  const double knots_speed[] = {std::log(0.01), std::log(0.02), std::log(0.04), std::log(0.08),
                                std::log(0.16)};
  const double knots_force[] = {std::log(0.5), std::log(1.0), std::log(2.0)};
  Replay::Window w{};
  w.speed_mps = 0.03;  // between knots 1 and 2 of speed: ln-interpolated weights
  w.force_N = 1.0;     // exactly on knot 1 of force
  double out_s[4] = {}, out_f[2] = {};
  sp->VibrationFeatures(knots_speed, w, out_s);
  fo->VibrationFeatures(knots_force, w, out_f);
  const double u = (std::log(0.03) - std::log(0.02)) / (std::log(0.04) - std::log(0.02));
  EXPECT_NEAR(out_s[0], 1 - u, 1e-12);  // hat of knot 1
  EXPECT_NEAR(out_s[1], u, 1e-12);      // hat of knot 2
  EXPECT_NEAR(out_s[2], 0, 1e-12);
  EXPECT_NEAR(out_f[0], 1, 1e-12);
  EXPECT_NEAR(out_f[1], 0, 1e-12);
  // Beyond the last knot the features are clamped (no extrapolation).
  w.speed_mps = 0.5;
  sp->VibrationFeatures(knots_speed, w, out_s);
  EXPECT_EQ(out_s[3], 1);
}

TEST(VibrationAxisEffect, KnotsSpanTheMeasuredSpeedsAndLoads) {
  const auto r = MakeWindows([](int, const Replay::Window&) { return 0.0; });
  double v_lo = 1e9, v_hi = 0, f_lo = 1e9, f_hi = 0;
  for (const auto& w : r.windows) {
    v_lo = std::min(v_lo, w.speed_mps), v_hi = std::max(v_hi, w.speed_mps);
    f_lo = std::min(f_lo, w.force_N), f_hi = std::max(f_hi, w.force_N);
  }
  const auto sp = FindEffect(effect::kVibrationSpeed)->Params(r);
  const auto fo = FindEffect(effect::kVibrationForce)->Params(r);
  ASSERT_EQ(sp.size(), 5u);
  ASSERT_EQ(fo.size(), 3u);
  EXPECT_NEAR(sp.front().init, std::log(v_lo), 1e-12);
  EXPECT_NEAR(sp.back().init, std::log(v_hi), 1e-12);
  EXPECT_NEAR(fo.front().init, std::log(f_lo), 1e-12);
  EXPECT_NEAR(fo.back().init, std::log(f_hi), 1e-12);
  for (std::size_t k = 0; k < sp.size(); ++k) {
    EXPECT_FALSE(sp[k].fitted);
    EXPECT_EQ(sp[k].name, "knot" + std::to_string(k));
    if (k > 0) {
      EXPECT_GT(sp[k].init, sp[k - 1].init);
    }
  }
}

TEST(VibrationAxisEffect, FitReproducesPowerLawsInSpeedAndLoad) {
  // Band power ~ v^(2 + 0.2 b) f^0.8: linear in ln v and ln f, which the hats represent exactly.
  const auto law = [](int b, const Replay::Window& w) {
    return -3 + 0.3 * b + (2 + 0.2 * b) * std::log(w.speed_mps) + 0.8 * std::log(w.force_N);
  };
  const auto r = MakeWindows(law);
  Model bank = ModelOf({"vibration-speed", "vibration-force"}, r);
  const auto rep = Fit(&bank, r, {.normal = false, .friction = false});
  ASSERT_NE(rep.Find(Channel::kVibration), nullptr);
  EXPECT_TRUE(rep.Find(Channel::kVibration)->summary.usable);
  Model flat;
  Fit(&flat, r, {.normal = false, .friction = false});
  const auto p = Predict(bank, r), q = Predict(flat, r);
  double e_bank = 0, e_flat = 0;
  int n = 0;
  for (std::size_t w = 0; w < r.windows.size(); ++w)
    for (int b = 0; b < 8; ++b, ++n) {
      const double truth = law(b, r.windows[w]);
      e_bank += std::pow(std::log(p.band_power[w][b]) - truth, 2);
      e_flat += std::pow(std::log(q.band_power[w][b]) - truth, 2);
    }
  // The ridge on the effect columns (workbench_fit.cpp) shrinks the slopes by a few per cent.
  EXPECT_LT(std::sqrt(e_bank / n), 0.1);
  EXPECT_GT(std::sqrt(e_flat / n), 1.5);
}

struct Reported {
  double lo_db, hi_db, correlation;
};
Reported Parse(const std::string& pattern) {
  static const std::regex re(
      R"(residual is ([+-][0-9.]+) dB at .* and ([+-][0-9.]+) dB at .*ln \S+ ([+-][0-9.]+)\))");
  std::smatch m;
  if (!std::regex_search(pattern, m, re)) ADD_FAILURE() << "unexpected evidence: " << pattern;
  return m.empty() ? Reported{0, 0, 0}
                   : Reported{std::stod(m[1]), std::stod(m[2]), std::stod(m[3])};
}

// Binned means of the per-window residual in dB, first and last bins with >= 5 windows.
std::pair<double, double> EndBins(const std::vector<double>& db, const std::vector<double>& key,
                                  const std::vector<double>& edges) {
  std::vector<double> sum(edges.size() - 1, 0);
  std::vector<int> n(edges.size() - 1, 0);
  for (std::size_t w = 0; w < db.size(); ++w)
    for (std::size_t j = 0; j + 1 < edges.size(); ++j)
      if (key[w] >= edges[j] && key[w] < edges[j + 1]) sum[j] += db[w], ++n[j];
  int lo = -1, hi = -1;
  for (int j = 0; j < static_cast<int>(n.size()); ++j)
    if (n[j] >= 5) hi = j, lo = lo < 0 ? j : lo;
  return {sum[lo] / n[lo], sum[hi] / n[hi]};
}

TEST(VibrationAxisEffect, EvidenceReportsTheResidualAtBothEndsOfItsAxis) {
  const auto speedy = MakeWindows(
      [](int b, const Replay::Window& w) { return 0.1 * b + 2 * std::log(w.speed_mps); }, 0.2, 7);
  Model flat;
  Fit(&flat, speedy, {.normal = false, .friction = false});
  const auto res = ComputeResiduals(flat, speedy, Predict(flat, speedy));
  const auto note = FindEffect(effect::kVibrationSpeed)->Evidence(speedy, res);
  const auto got = Parse(note.pattern);
  std::vector<double> speed;
  for (const auto& w : speedy.windows) speed.push_back(w.speed_mps);
  const auto [lo, hi] =
      EndBins(WindowResidualDb(flat, speedy), speed, {0.01, 0.02, 0.04, 0.08, 0.16, 1});
  EXPECT_NEAR(got.lo_db, lo, 0.051) << note.pattern;
  EXPECT_NEAR(got.hi_db, hi, 0.051) << note.pattern;
  // The level is set so that the predicted power matches on average (workbench_fit.cpp), so the
  // fast end, which dominates the mean power, sits near 0 dB; v^2 over the end bins' 13-fold range
  // of mean speeds is about 22 dB from end to end.
  EXPECT_GT(hi - lo, 18);
  EXPECT_GT(got.correlation, 0.9);
  // On the load axis the same data show no trend: the same offset at both ends.
  const auto none = Parse(FindEffect(effect::kVibrationForce)->Evidence(speedy, res).pattern);
  EXPECT_LT(std::abs(none.correlation), 0.2);
  EXPECT_LT(std::abs(none.hi_db - none.lo_db), 1.0);
  // Once the speed axis is modelled its own evidence is nearly flat (the ridge on the effect
  // columns leaves a few per cent of the trend).
  Model bank = ModelOf({"vibration-speed"}, speedy);
  Fit(&bank, speedy, {.normal = false, .friction = false});
  const auto after = Parse(EvidenceOf(effect::kVibrationSpeed, bank, speedy).pattern);
  EXPECT_LT(std::abs(after.hi_db - after.lo_db), 0.1 * (hi - lo))
      << after.lo_db << " " << after.hi_db << " " << after.correlation;
  EXPECT_LT(std::abs(after.lo_db), 1.0);
  EXPECT_LT(std::abs(after.hi_db), 1.0);
}

}  // namespace
}  // namespace hapticlab::modeling::wb::vibration_axis_test
