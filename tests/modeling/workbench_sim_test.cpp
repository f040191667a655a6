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
#include "hapticlab/core/status.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/sim_truth/friction.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::wb::workbench_sim_test {
namespace {

// parameters the workbench must reproduce the simulator's noise-free forces.
TEST(WorkbenchSimulator, TruthModelReproducesTheIndependentSimulator) {
  TruthParams t;
  t.effects = BaselineEffects();
  for (const char* e : {"stribeck", "anisotropic-friction", "load-dependent-friction",
                        "position-dependent-friction", "base-layer"})
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
    et +=
        std::pow(p.ftx_N[i] - sim.ftx_clean[row], 2) + std::pow(p.fty_N[i] - sim.fty_clean[row], 2);
    sn += std::pow(sim.fn_clean[row], 2);
    st += std::pow(sim.ftx_clean[row], 2) + std::pow(sim.fty_clean[row], 2);
  }
  // What remains: force noise on the measured load that scales the friction, Euler substeps.
  EXPECT_LT(std::sqrt(en / sn), 1e-6);
  EXPECT_LT(std::sqrt(et / st), 0.01);
}

// The truth's values come from the effects' declarations (Effect::TruthSpecs): defaults, and
// a value no effect declares, or outside its bounds, is refused before anything is simulated.
TEST(WorkbenchSimulator, TruthValuesAreTheEffectsDeclarations) {
  TruthParams t;
  EXPECT_EQ(t.Get(key::kMuK), 0.3) << "coulomb's declared default";
  EXPECT_EQ(t.Get(truth_key::kWavelength_m), 0.4e-3);
  t.Set(key::kMuK, 0.45);
  EXPECT_EQ(t.Get(key::kMuK), 0.45);
  EXPECT_THROW(t.Get({"coulomb", "no-such"}), PreconditionError);
  EXPECT_THROW(t.Get({"no-such-effect", "mu_k"}), PreconditionError);
  t.duration_s = 1;
  EXPECT_NO_THROW(Simulate(t));
  const std::pair<ParamKey, double> bad[] = {{key::kMuK, -0.1},
                                             {key::kMuK, std::nan("")},
                                             {key::kLoadAlpha, 1e100},
                                             {{"coulomb", "no-such"}, 1},
                                             {{"no-such-effect", "x"}, 1}};
  for (const auto& [k, v] : bad) {
    TruthParams b = t;
    b.Set(k, v);
    EXPECT_THROW(Simulate(b), PreconditionError) << k.effect << "." << k.name << " = " << v;
  }
  TruthParams unknown = t;
  unknown.effects = {"coulomb", "wobble"};
  EXPECT_THROW(Simulate(unknown), PreconditionError);
}

// The truth's friction law (hapticlab::sim_truth) used by this simulator and the simulated rig:
// the rig's ratio form maps exactly onto the additive form.
TEST(WorkbenchSimulator, TruthFrictionLawMapsTheRatioForm) {
  const auto law = sim_truth::StribeckFriction::FromRatio(0.3, 1.5, 0.004);
  EXPECT_NEAR(law.dmu_s, 0.15, 1e-15);
  EXPECT_NEAR(law.Mu(0), 0.45, 1e-15);  // static: mu_k * ratio
  EXPECT_NEAR(law.Mu(0.004), 0.3 + 0.15 * std::exp(-1.0), 1e-15);
  EXPECT_NEAR(law.Mu(1.0), 0.3, 1e-15);  // far above v_s: kinetic
  for (const double v : {0.0, 0.001, 0.003, 0.01})
    EXPECT_NEAR(law.Mu(v), 0.3 * (1 + 0.5 * std::exp(-std::pow(v / 0.004, 2))), 1e-15) << v;
}

}  // namespace
}  // namespace hapticlab::modeling::wb::workbench_sim_test
