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
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::wb {
namespace {

TEST(WorkbenchCatalogue, HasEveryNamedEffectWithDescriptionsAndSaneParameters) {
  const std::vector<std::string> required = {"coulomb", "viscous", "dahl", "stribeck", "anisotropic-friction",
                                             "load-dependent-friction", "position-dependent-friction", "hc-damping",
                                             "hc-exponent", "base-layer", "vibration-speed", "vibration-force",
                                             "vibration-direction"};
  std::set<std::string> names;
  for (const auto& e : Catalogue()) EXPECT_TRUE(names.insert(std::string(e->name())).second) << e->name();
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

}  // namespace
}  // namespace hapticlab::modeling::wb
