// effects/vibration_direction.cpp: vibration that depends on the direction of motion, first and
// second harmonics of the direction (cos phi, sin phi, cos 2phi, sin 2phi over the window)
// added to every band's ln power.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "strokes.hpp"

namespace hapticlab::modeling::wb::vibration_direction_test {
namespace {
using namespace effect_test;

TEST(VibrationDirectionEffect, FeaturesAreTheWindowsDirectionHarmonics) {
  const Effect* e = FindEffect(effect::kVibrationDirection);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->channel(), Channel::kVibration);
  EXPECT_EQ(e->VibrationColumns(), 4);
  EXPECT_TRUE(e->Params(Replay{}).empty()) << "no parameters of its own, only coefficients";
  Replay::Window w{};
  w.dir = {0.1, -0.2, 0.3, -0.4};
  double out[4] = {};
  e->VibrationFeatures(nullptr, w, out);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(out[i], w.dir[static_cast<std::size_t>(i)]);
}

TEST(VibrationDirectionEffect, FitReproducesGroovesThatVibrateAcrossNotAlong) {
  // Grooves along y: stroking along x (across) is 1.2 nepers (10.4 dB) louder than along y.
  const auto law = [](int b, const Replay::Window& w) {
    return -2 - 0.2 * b + 0.6 * w.dir[2] + 0.15 * w.dir[0];
  };
  const auto r = MakeWindows(law, 0.1, 9);
  Model m = ModelOf({"vibration-direction"}, r);
  const auto rep = Fit(&m, r, {.normal = false, .friction = false});
  EXPECT_TRUE(rep.IsUsable());
  const auto p = Predict(m, r);
  double e = 0;
  int n = 0;
  for (std::size_t w = 0; w < r.windows.size(); ++w)
    for (int b = 0; b < 8; ++b, ++n)
      e += std::pow(std::log(p.band_power[w][b]) - law(b, r.windows[w]), 2);
  EXPECT_LT(std::sqrt(e / n), 0.06);
  // The cos 2phi coefficient of every band is near the truth's 0.6 (ridge-shrunk by < 10 %).
  const auto& c = m.coef.at(std::string(effect::kVibrationDirection));
  ASSERT_EQ(c.size(), 8u * 4);
  for (int b = 0; b < 8; ++b) EXPECT_NEAR(c[b * 4 + 2], 0.6, 0.06) << b;
}

TEST(VibrationDirectionEffect, EvidenceNamesTheLoudestAxisOfMotion) {
  const auto r = MakeWindows([](int, const Replay::Window& w) { return 0.8 * w.dir[2]; }, 0.1, 10);
  Model flat;
  Fit(&flat, r, {.normal = false, .friction = false});
  const auto note = EvidenceOf(effect::kVibrationDirection, flat, r);
  // Loudest along the x axis (axial bins centred on +-22.5 deg), quietest along y (+-67.5 deg).
  const auto at = note.pattern.find("strokes along ");
  ASSERT_NE(at, std::string::npos) << note.pattern;
  EXPECT_NEAR(std::abs(std::stod(note.pattern.substr(at + 14))), 22.5, 1) << note.pattern;
  const auto last = note.pattern.rfind("along ");
  EXPECT_NEAR(std::abs(std::stod(note.pattern.substr(last + 6))), 67.5, 1) << note.pattern;
  EXPECT_NE(note.pattern.find("is +"), std::string::npos) << note.pattern;
}

}  // namespace
}  // namespace hapticlab::modeling::wb::vibration_direction_test
