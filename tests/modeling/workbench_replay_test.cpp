// Workbench replay: blocks, vibration windows, `measurement check`.

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::wb::workbench_replay_test {
namespace {

TEST(WorkbenchReplay, SplitsIntoAlternateBlocksAndSteadyVibrationWindows) {
  TruthParams t;
  t.duration_s = 20;
  const auto sim = Simulate(t);
  const auto r = PrepareReplay(sim.m);
  EXPECT_NEAR(r.rate_hz, 500, 1e-6);
  int train = 0, held = 0;
  for (const auto& s : r.samples()) (s.block % 2 ? held : train) += s.contact;
  EXPECT_GT(train, 1000);
  EXPECT_GT(held, 1000);
  ASSERT_TRUE(r.has_vibration);
  ASSERT_GT(r.windows.size(), 20u);
  for (const auto& w : r.windows) {
    EXPECT_GE(w.speed_mps, 0.01);
    EXPECT_EQ(w.band_power.size(), r.band_lo_hz.size());
  }
  Measurement air = sim.m;
  for (auto& row : air.rows) row.f_N.setZero();
  try {
    PrepareReplay(air);
    FAIL() << "no contact must be an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fz_N"), std::string::npos) << e.what();
  }
}

// The simulator and the workbench implement the physics independently; with the truth's

// The positions the Dahl bristle follows: the window chosen per sample (intersection of
// confidence intervals) smooths the noise at rest like the 20 ms window and follows a fast, short
// stroke (4 mm at 120 mm/s peak, 67 ms), which the fixed 20 ms quadratic window rounds by ~3 um.
TEST(WorkbenchReplay, AdaptivePositionWindowSmoothsRestAndFollowsFastStrokes) {
  const double sigma_m = 1e-7, len_m = 4e-3, T_s = 2 * len_m / 0.12;
  const double pi = 3.14159265358979323846;
  Measurement m;
  m.file = "stroke.csv";
  std::vector<double> truth;
  Rng rng(5);
  for (int k = 0; k < 2067; ++k) {
    const double t = (k - 1000) * 1e-3, tau = std::clamp(t / T_s, 0.0, 1.0);
    truth.push_back(len_m * (tau - std::sin(2 * pi * tau) / (2 * pi)));
    MeasurementRow r;
    r.t_s = k * 1e-3;
    r.p_m = {truth.back() + rng.Normal(0, sigma_m), rng.Normal(0, sigma_m), -1e-4};
    r.v_mps = {tau > 0 && tau < 1 ? 0.12 * std::pow(std::sin(pi * tau), 2) : 0.0, 0, 0};
    r.f_N = {0, 0, 1.0};
    m.rows.push_back(r);
  }
  ReplayOptions fixed;
  fixed.position_adaptive = false;
  const auto a = PrepareReplay(m), f = PrepareReplay(m, fixed);
  double rest_a = 0, rest_f = 0, stroke_a = 0, stroke_f = 0;
  int n_rest = 0;
  for (std::size_t i = 0; i < a.samples().size(); ++i) {
    const auto row = static_cast<std::size_t>(a.samples()[i].row);
    const double ea = a.samples()[i].x_m - truth[row], ef = f.samples()[i].x_m - truth[row];
    if (row >= 100 && row < 900)
      rest_a += ea * ea, rest_f += ef * ef, ++n_rest;
    else if (row >= 1000 && row < 1067)
      stroke_a = std::max(stroke_a, std::abs(ea)), stroke_f = std::max(stroke_f, std::abs(ef));
  }
  rest_a = std::sqrt(rest_a / n_rest), rest_f = std::sqrt(rest_f / n_rest);
  // At rest: the 21-row window's noise is 0.33 sigma; raw rows would be 1 sigma.
  EXPECT_LT(rest_a, 0.5 * sigma_m);
  EXPECT_LT(rest_f, 0.5 * sigma_m);
  // In the stroke: the rule keeps an estimate within 2 x 2 sigma of the raw row, itself within
  // ~3.5 sigma of the path over 34 samples; the fixed window is off by microns.
  EXPECT_LT(stroke_a, 8 * sigma_m);
  EXPECT_GT(stroke_f, 15 * sigma_m);
}

TEST(WorkbenchMeasurement, SummaryReportsRateRangesAndGaps) {
  TruthParams t;
  t.duration_s = 5;
  auto sim = Simulate(t);
  auto& rows = sim.m.rows;
  rows.erase(rows.begin() + 4000, rows.begin() + 4100);  // a 50 ms gap
  sim.m.row_lines.erase(sim.m.row_lines.begin() + 4000, sim.m.row_lines.begin() + 4100);
  const auto s = Summarize(sim.m);
  EXPECT_NEAR(s.rate_hz, 2000, 1e-6);
  EXPECT_EQ(s.gaps, 1);
  EXPECT_NEAR(s.max_gap_s, 0.0505, 1e-9);
  ASSERT_FALSE(s.warnings.empty());
  EXPECT_NE(s.warnings[0].find("line 4101"), std::string::npos) << s.warnings[0];
  EXPECT_GT(s.ranges.at("fz_N").second, 0.3);
}

}  // namespace
}  // namespace hapticlab::modeling::wb::workbench_replay_test
