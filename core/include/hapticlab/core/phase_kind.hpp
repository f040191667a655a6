#pragma once
/// @file The kinds of study phase, shared by the protocol (`[[phase]] kind`), the plan and the
/// study record (the trial table's `phase` column holds a kind's name). In core because
/// protocols and db both speak it and neither depends on the other.

#include "hapticlab/core/enum_names.hpp"

namespace hapticlab {

/// kStaircase and kQuestPlus are adaptive phases (protocols/adaptive.hpp): their trials are
/// not planned ahead but chosen one by one from the answers so far.
enum class PhaseKind { kTraining, kReference, kMain, kStaircase, kQuestPlus };
inline constexpr EnumTable<PhaseKind, 5> kPhaseKindNames{{{PhaseKind::kTraining, "training"},
                                                          {PhaseKind::kReference, "reference"},
                                                          {PhaseKind::kMain, "main"},
                                                          {PhaseKind::kStaircase, "staircase"},
                                                          {PhaseKind::kQuestPlus, "quest-plus"}}};

}  // namespace hapticlab
