// Workbench replay: blocks, vibration windows, `measurement check`.

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::wb {
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
}  // namespace hapticlab::modeling::wb
