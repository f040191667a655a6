// Workbench ground-truth simulator against the workbench's own physics.

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

// parameters the workbench must reproduce the simulator's noise-free forces.
TEST(WorkbenchSimulator, TruthModelReproducesTheIndependentSimulator) {
  TruthParams t;
  t.effects = BaselineEffects();
  for (const char* e : {"stribeck", "anisotropic-friction", "load-dependent-friction", "position-dependent-friction",
                        "base-layer"})
    t.effects.push_back(e);
  t.duration_s = 30;
  t.pos_noise_m = t.vel_noise_mps = 0;  // exact kinematics: only the implementations differ
  const auto sim = Simulate(t);
  const auto r = PrepareReplay(sim.m);
  const auto p = Predict(TruthModel(sim, r), r);
  double en = 0, et = 0, sn = 0, st = 0;
  for (std::size_t i = 0; i < r.samples().size(); ++i) {
    if (!r.samples()[i].contact) continue;
    const int row = r.samples()[i].row;
    en += std::pow(p.fn_N[i] - sim.fn_clean[row], 2);
    et += std::pow(p.ftx_N[i] - sim.ftx_clean[row], 2) + std::pow(p.fty_N[i] - sim.fty_clean[row], 2);
    sn += std::pow(sim.fn_clean[row], 2);
    st += std::pow(sim.ftx_clean[row], 2) + std::pow(sim.fty_clean[row], 2);
  }
  // What remains: force noise on the measured load that scales the friction, Euler substeps.
  EXPECT_LT(std::sqrt(en / sn), 1e-6);
  EXPECT_LT(std::sqrt(et / st), 0.01);
}

}  // namespace
}  // namespace hapticlab::modeling::wb
