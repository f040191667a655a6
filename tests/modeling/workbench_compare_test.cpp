// Workbench `compare`: the breakdown by regime shows where a model fails.

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

TEST(WorkbenchCompare, BreakdownShowsWhereTheModelFails) {
  // Hidden Stribeck: the baseline under-predicts friction at low speed only.
  TruthParams t;
  t.duration_s = 60;
  t.effects = BaselineEffects();
  t.effects.push_back("stribeck");
  t.stribeck_dmu = 0.3;
  const auto sim = Simulate(t);
  const auto r = PrepareReplay(sim.m);
  Model m;
  AddEffects(&m, BaselineEffects(), r);
  Fit(&m, r);
  const auto c = Compare(m, r);
  const auto& sp = c.breakdown.at("speed").at("friction_N");
  // Bins: 0-0.5, 0.5-3, 3-10, 10-30, 30-60, 60-100 ... mm/s.
  ASSERT_GT(sp[1].n, 50);
  ASSERT_GT(sp[5].n, 50);
  EXPECT_GT(sp[1].mean, sp[5].mean + 0.05) << "excess friction at 0.5-3 mm/s against 60-100 mm/s";
  for (const char* dim : {"regime", "speed", "load", "direction", "position", "time", "band"})
    EXPECT_TRUE(c.breakdown.count(dim)) << dim;
  EXPECT_GT(c.errors.overall, 0);
  EXPECT_TRUE(c.errors.normal_force.present && c.errors.friction.present &&
              c.errors.vibration.present);
  EXPECT_EQ(c.errors.Normalized().size(), 3u);
}

}  // namespace
}  // namespace hapticlab::modeling::wb
