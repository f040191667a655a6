// effects/registry.cpp: the catalogue lists every effect source once, with the channel and the
// dependencies its physics implies.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <string>

#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::modeling::wb::registry_test {
namespace {

TEST(EffectRegistry, ListsEverySourceFileOnceInAFixedOrder) {
  // One effect per file of modeling/src/effects/ (vibration_axis.cpp holds both axes).
  std::multiset<std::string> from_files;
  for (const auto& f :
       std::filesystem::directory_iterator(std::string(HL_SOURCE_DIR) + "/modeling/src/effects")) {
    if (f.path().extension() != ".cpp") continue;
    std::string stem = f.path().stem().string();
    if (stem == "registry" || stem == "effect_util") continue;
    if (stem == "vibration_axis") {
      from_files.insert("vibration-speed");
      from_files.insert("vibration-force");
      continue;
    }
    std::replace(stem.begin(), stem.end(), '_', '-');
    from_files.insert(stem);
  }
  std::multiset<std::string> listed;
  for (const auto& e : Catalogue()) listed.insert(std::string(e->name()));
  EXPECT_EQ(listed, from_files);
  EXPECT_EQ(std::set<std::string>(listed.begin(), listed.end()).size(), listed.size())
      << "each effect once";
  // The same objects every call (a static catalogue), lookups by name.
  EXPECT_EQ(&Catalogue(), &Catalogue());
  for (const auto& e : Catalogue()) EXPECT_EQ(FindEffect(e->name()), e.get());
  EXPECT_EQ(FindEffect("core"), nullptr) << "the core is not an entry: every model has it";
  EXPECT_EQ(FindEffect(""), nullptr);
  EXPECT_EQ(std::string(Catalogue().front()->name()), "coulomb");
  EXPECT_EQ(CatalogueNames().find("coulomb, viscous, dahl, stribeck"), 0u);
}

TEST(EffectRegistry, ChannelsAndDependenciesFollowThePhysics) {
  const std::map<std::string, Channel> channel = {
      {"coulomb", Channel::kFriction},
      {"viscous", Channel::kFriction},
      {"dahl", Channel::kFriction},
      {"stribeck", Channel::kFriction},
      {"anisotropic-friction", Channel::kFriction},
      {"load-dependent-friction", Channel::kFriction},
      {"position-dependent-friction", Channel::kFriction},
      {"hc-damping", Channel::kNormal},
      {"hc-exponent", Channel::kNormal},
      {"base-layer", Channel::kNormal},
      {"vibration-speed", Channel::kVibration},
      {"vibration-force", Channel::kVibration},
      {"vibration-direction", Channel::kVibration}};
  // Effects that shape the Coulomb level f_C need the coulomb effect's mu_k.
  const std::set<std::string> modify_coulomb = {"dahl", "stribeck", "anisotropic-friction",
                                                "load-dependent-friction",
                                                "position-dependent-friction"};
  ASSERT_EQ(Catalogue().size(), channel.size());
  for (const auto& e : Catalogue()) {
    const std::string n(e->name());
    ASSERT_TRUE(channel.count(n)) << n;
    EXPECT_EQ(e->channel(), channel.at(n)) << n;
    const auto deps = e->requires_effects();
    if (modify_coulomb.count(n)) {
      ASSERT_EQ(deps.size(), 1u) << n;
      EXPECT_EQ(deps[0], "coulomb") << n;
    } else {
      EXPECT_TRUE(deps.empty()) << n;
    }
    EXPECT_EQ(e->VibrationColumns() > 0, e->channel() == Channel::kVibration) << n;
  }
}

}  // namespace
}  // namespace hapticlab::modeling::wb::registry_test
