#pragma once
// The declared field tables of the protocol file (core/fields.hpp): every key of every table
// with its type, unit, range and meaning, read by protocol.cpp and adaptive.cpp and printed
// into docs/formats.md by ProtocolKeyTables().

#include <span>
#include <string_view>

#include "hapticlab/core/fields.hpp"
#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::protocols::internal {

inline constexpr std::string_view kPhaseKinds = "training|reference|main|staircase|quest-plus";
// `kind`'s choice i is PhaseKind(i), stored by its name: the choices are kPhaseKindNames'
// names, in the enum's order.
constexpr bool PhaseChoicesAreTheKindNames() {
  std::string_view rest = kPhaseKinds;
  for (std::size_t i = 0; i < kPhaseKindNames.size(); ++i) {
    const auto& e = kPhaseKindNames[i];
    if (static_cast<std::size_t>(e.value) != i || !rest.starts_with(e.name)) return false;
    rest.remove_prefix(e.name.size());
    if (!rest.empty() && !rest.starts_with('|')) return false;
    if (!rest.empty()) rest.remove_prefix(1);
  }
  return rest.empty();
}
static_assert(PhaseChoicesAreTheKindNames());

std::span<const fields::Field<Protocol>> TopLevelFields();
std::span<const fields::Field<Protocol>> StudyFields();
std::span<const fields::Field<Material>> MaterialFields();
/// What a [[material]] holds before its keys are read.
Material MaterialDefaults();
std::span<const fields::Field<Method>> MethodFields();
std::span<const fields::Field<Phase>> PhaseFields();
std::span<const fields::Field<Randomization>> RandomizationFields();
std::span<const fields::Field<Protocol>> BreakFields();
std::span<const fields::Field<Protocol>> MaskingFields();
std::span<const fields::Field<Protocol>> ConsentFields();
std::span<const fields::Field<Protocol>> AnalysisFields();
// Adaptive [[phase]] tables (adaptive.cpp): the keys of both kinds, then each kind's own.
std::span<const fields::Field<AdaptiveSpec>> AdaptiveFields();
std::span<const fields::Field<AdaptiveSpec>> StaircaseFields();
std::span<const fields::Field<AdaptiveSpec>> QuestPlusFields();
std::span<const fields::Field<psychophysics::SimulatedObserverParams>> ObserverFields();

}  // namespace hapticlab::protocols::internal
