#pragma once
/// @file The one JSON form of a participant's plan: what `hapticlab study plan --json` prints
/// and what a session's provenance stores (`session.plan_json`, docs/studies.md).

#include <nlohmann/json.hpp>
#include <vector>

#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::runner {

/// One object per planned trial, in plan order: `trial` (1-based, as the console and the log
/// number trials), `plan_index` (0-based, the database's trial.plan_index), `phase`,
/// `material`, `comparison`, `method`, `repetition`, `left`, `right`, `rated`, `break_before`.
nlohmann::json PlanToJson(const std::vector<protocols::PlannedTrial>& plan);

}  // namespace hapticlab::runner
