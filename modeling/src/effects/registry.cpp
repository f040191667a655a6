// The effect catalogue (workbench_model.hpp). Adding an effect: write effects/<name>.cpp with a
// Make<Name>() factory and add one X(<Name>) line below; the folder is compiled by a glob
// (docs/workbench.md, "Adding an effect").
#include <algorithm>

#include "hapticlab/core/status.hpp"
#include "hapticlab/modeling/workbench.hpp"

// One line per effect, in catalogue order.
#define HL_BUILT_IN_EFFECTS(X) \
  X(Coulomb)                   \
  X(Viscous)                   \
  X(Dahl)                      \
  X(Stribeck)                  \
  X(AnisotropicFriction)       \
  X(LoadDependentFriction)     \
  X(PositionDependentFriction) \
  X(HcDamping)                 \
  X(HcExponent)                \
  X(BaseLayer)                 \
  X(VibrationSpeed)            \
  X(VibrationForce)            \
  X(VibrationDirection)

namespace hapticlab::modeling::wb {

#define HL_DECLARE_EFFECT(Name) std::unique_ptr<Effect> Make##Name();
HL_BUILT_IN_EFFECTS(HL_DECLARE_EFFECT)
#undef HL_DECLARE_EFFECT

namespace {
std::vector<std::unique_ptr<Effect>>& Registry() {
  static std::vector<std::unique_ptr<Effect>> catalogue = [] {
    std::vector<std::unique_ptr<Effect>> v;
#define HL_ADD_EFFECT(Name) v.push_back(Make##Name());
    HL_BUILT_IN_EFFECTS(HL_ADD_EFFECT)
#undef HL_ADD_EFFECT
    return v;
  }();
  return catalogue;
}
}  // namespace

const std::vector<std::unique_ptr<Effect>>& Catalogue() { return Registry(); }

EffectRegistration::EffectRegistration(std::unique_ptr<Effect> effect) {
  HL_REQUIRE(effect != nullptr, "EffectRegistration needs an effect");
  name_ = std::string(effect->name());
  HL_REQUIRE(!name_.empty() && name_ != effect::kCore && FindEffect(name_) == nullptr,
             "effect '" + name_ + "' is registered twice (or is the core's name)");
  Registry().push_back(std::move(effect));
}

EffectRegistration::~EffectRegistration() {
  auto& v = Registry();
  v.erase(std::remove_if(v.begin(), v.end(), [&](const auto& e) { return e->name() == name_; }),
          v.end());
}

}  // namespace hapticlab::modeling::wb
