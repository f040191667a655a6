// Scoring a vibration model on a recording (vibration_score.hpp): the right texture scores
// lower than a wrong one, the level ratio follows the recording's level, and
// level-normalised E_s does not depend on it.

#include "hapticlab/modeling/vibration_score.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/vibration.hpp"

namespace hapticlab::modeling::vibration_score_test {
namespace {

// AR(2) with a resonance at `peak` (fraction of the sample rate), pole radius 0.95.
std::vector<double> Texture(double peak, std::size_t n, std::uint64_t seed) {
  Rng rng(seed);
  const double c1 = 2 * 0.95 * std::cos(2 * std::numbers::pi * peak), c2 = -0.95 * 0.95;
  std::vector<double> x(n);
  double a1 = 0, a2 = 0;
  for (auto& v : x) {
    v = c1 * a1 + c2 * a2 + rng.Normal();
    a2 = a1;
    a1 = v;
  }
  return x;
}

renderer::MaterialModel Model(double peak, std::uint64_t seed) {
  renderer::MaterialModel m;
  m.vibration = FitVibrationBank({{"fit", 0.1, 1.0, 4000, Texture(peak, 40000, seed)}}, {});
  return m;
}

TEST(VibrationScore, TheRightTextureScoresLowestAndLevelsAreRatios) {
  const auto low = Model(0.05, 1), high = Model(0.15, 2);  // 200 Hz and 600 Hz at 4 kHz
  Recording r{"rec", 0.1, 1.0, 4000, Texture(0.05, 40000, 3)};
  const auto right = ScoreVibration(low, r), wrong = ScoreVibration(high, r);
  EXPECT_EQ(right.kind, "ar bank");
  EXPECT_LT(right.es, 0.3);
  EXPECT_GT(wrong.es, 2 * right.es);
  EXPECT_NEAR(right.level_ratio, 1.0, 0.15);
  // Three times louder: the level ratio is a third; normalised E_s is unchanged.
  Recording loud = r;
  for (auto& v : loud.acc) v *= 3;
  const auto l = ScoreVibration(low, loud);
  EXPECT_NEAR(l.level_ratio, right.level_ratio / 3, 1e-9);
  EXPECT_GT(l.es, 0.5);  // unnormalised E_s punishes the level
  const auto n1 = ScoreVibration(low, r, {.level_normalised = true});
  const auto n3 = ScoreVibration(low, loud, {.level_normalised = true});
  EXPECT_NEAR(n1.es, n3.es, 1e-6 * n1.es);  // the resampler is linear to rounding
}

TEST(VibrationScore, UnlabelledRecordingsTakeAOneCellModelsConditionOnly) {
  const auto low = Model(0.05, 1);
  Recording r{"rec", 0, 0, 4000, Texture(0.05, 20000, 3)};
  r.labelled = false;
  const auto s = ScoreVibration(low, r);
  EXPECT_TRUE(s.condition_from_model);
  EXPECT_EQ(s.speed_mps, 0.1);
  renderer::MaterialModel two;
  two.vibration = FitVibrationBank({{"a", 0.1, 1.0, 4000, Texture(0.05, 20000, 1)},
                                    {"b", 0.2, 1.0, 4000, Texture(0.05, 20000, 2)}},
                                   {});
  try {
    ScoreVibration(two, r);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().front().file, "rec");
    EXPECT_EQ(e.diagnostics().front().field, "speed_mps");
  }
}

}  // namespace
}  // namespace hapticlab::modeling::vibration_score_test
