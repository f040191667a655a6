// Workbench models: the effect catalogue, adding effects, unknown names.

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
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::wb::workbench_model_test {
namespace {

TEST(WorkbenchCatalogue, HasEveryNamedEffectWithDescriptionsAndSaneParameters) {
  const std::vector<std::string> required = {"coulomb",
                                             "viscous",
                                             "dahl",
                                             "stribeck",
                                             "anisotropic-friction",
                                             "load-dependent-friction",
                                             "position-dependent-friction",
                                             "hc-damping",
                                             "hc-exponent",
                                             "base-layer",
                                             "vibration-speed",
                                             "vibration-force",
                                             "vibration-direction"};
  std::set<std::string> names;
  for (const auto& e : Catalogue())
    EXPECT_TRUE(names.insert(std::string(e->name())).second) << e->name();
  for (const auto& n : required) EXPECT_TRUE(names.count(n)) << n;
  TruthParams t;
  t.duration_s = 10;
  const auto sim = Simulate(t);
  const auto r = PrepareReplay(sim.m);
  for (const auto& e : Catalogue()) {
    EXPECT_GT(e->description().size(), 150u) << e->name() << ": one paragraph of physics";
    for (const auto& p : e->Params(r)) {
      EXPECT_LE(p.lo, p.init) << e->name() << "." << p.name;
      EXPECT_LE(p.init, p.hi) << e->name() << "." << p.name;
      EXPECT_GT(p.scale, 0) << e->name() << "." << p.name;
    }
    for (const auto dep : e->requires_effects()) EXPECT_NE(FindEffect(dep), nullptr);
  }
  Model m;
  EXPECT_THROW(AddEffects(&m, {"no-such-effect"}, r), PreconditionError);
  AddEffects(&m, {"stribeck"}, r);  // pulls in its prerequisite
  EXPECT_TRUE(m.Has("coulomb"));
}

// User-given names are checked at the edge: every unknown name, with the source and field.
TEST(WorkbenchCatalogue, UnknownNamesAreInputErrorsNamingSourceAndField) {
  EXPECT_NO_THROW(RequireKnownEffects({"coulomb", "vibration-force"}, "model.toml", "effects"));
  try {
    RequireKnownEffects({"coulomb", "wobble", "drag"}, "<command line>", "--add");
    FAIL() << "unknown names must throw";
  } catch (const InputError& e) {
    ASSERT_EQ(e.diagnostics().size(), 2u);
    EXPECT_EQ(e.diagnostics()[0].file, "<command line>");
    EXPECT_EQ(e.diagnostics()[0].field, "--add");
    EXPECT_NE(e.diagnostics()[0].message.find("'wobble'"), std::string::npos);
    EXPECT_NE(e.diagnostics()[1].message.find("'drag'"), std::string::npos);
    EXPECT_NE(e.diagnostics()[1].message.find("vibration-direction"), std::string::npos)
        << "lists the catalogue";
  }
}

// The keys declared once in workbench_params.hpp name parameters the catalogue really has.
TEST(WorkbenchParams, KeysNameParametersOfTheirEffects) {
  const Replay r;
  const ParamKey keys[] = {key::kK1mm_N,        key::kN,
                           key::kB1mm_Ns_per_m, key::kBaseK_N_per_m,
                           key::kLayer_m,       key::kMuK,
                           key::kMuB_Ns_per_m,  key::kKappa_N_per_m,
                           key::kStribeckDmu,   key::kStribeckSpeed_mps,
                           key::kLoadAlpha,     key::kAnisotropy[0],
                           key::kAnisotropy[1], key::kAnisotropy[2],
                           key::kAnisotropy[3], key::kTileX0_m,
                           key::kTileX1_m,      key::kTileY0_m,
                           key::kTileY1_m};
  Model all;
  std::vector<std::string> every;
  for (const auto& e : Catalogue()) every.emplace_back(e->name());
  AddEffects(&all, every, r);
  for (const auto& k : keys) {
    EXPECT_TRUE(k.effect == effect::kCore || all.Has(k.effect)) << k.effect;
    EXPECT_TRUE(std::isfinite(all.Get(k, std::nan("")))) << k.effect << "." << k.name;
  }
  EXPECT_THROW(Model{}.At(key::kMuK), PreconditionError);
}

// ContactParameters: the typed view reads only the effects a model lists, and its renderer
// units reproduce the workbench's law f_n = (d / 1 mm)^n (K1mm + B1mm d_dot) as d^n (K + B d_dot).
TEST(WorkbenchParams, ContactParametersViewAndRendererUnits) {
  Model m;
  m.effects = {std::string(effect::kCoulomb), std::string(effect::kHcExponent),
               std::string(effect::kHcDamping)};
  const ContactParameters in{.K1mm_N = 2.5,
                             .n = 1.6,
                             .B1mm_Ns_per_m = 12,
                             .mu_k = 0.4,
                             .mu_b_Ns_per_m = 0.7,
                             .kappa_N_per_m = 3000};
  in.ToModel(&m);
  EXPECT_EQ(m.At(key::kMuB_Ns_per_m), 0.7);  // written even though viscous is not listed
  const auto out = ContactParameters::From(m, /*no_dahl_kappa_N_per_m=*/1e6);
  EXPECT_EQ(out.K1mm_N, 2.5);
  EXPECT_EQ(out.n, 1.6);
  EXPECT_EQ(out.B1mm_Ns_per_m, 12);
  EXPECT_EQ(out.mu_k, 0.4);
  EXPECT_EQ(out.mu_b_Ns_per_m, 0) << "viscous is not in the model";
  EXPECT_EQ(out.kappa_N_per_m, 1e6) << "dahl is not in the model";
  const double d_m = 2.3e-3, ddot_mps = 0.01;
  const double workbench_N = std::pow(d_m / 1e-3, 1.6) * (2.5 + 12 * ddot_mps);
  const double renderer_N =
      std::pow(d_m, 1.6) * (out.K_N_per_m_pow_n() + out.B_Ns_per_m_pow_n_plus_1() * ddot_mps);
  EXPECT_NEAR(renderer_N, workbench_N, 1e-12 * workbench_N);
  m.effects.erase(m.effects.begin() + 1);  // without hc-exponent the law is linear
  EXPECT_EQ(ContactParameters::From(m).n, 1);
  EXPECT_NEAR(ContactParameters::From(m).K_N_per_m_pow_n(), 2500, 1e-9);
}

}  // namespace
}  // namespace hapticlab::modeling::wb::workbench_model_test
