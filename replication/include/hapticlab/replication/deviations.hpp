#pragma once
/// @file The "Preregistration and deviations from the plan" section of `hapticlab analyze
/// --plan PLAN` (docs/replication.md): the preregistered analyses apart from the exploratory
/// ones, the primary outcome, and every deviation of the recorded study from the plan:
/// - a protocol key that differs from the plan's protocol (protocols::CanonicalDifferences),
///   in the study's protocol or recorded by a session (provenance "plan_protocol_changes");
/// - a session recorded without the plan, or under another plan (provenance "plan_sha256");
/// - a material model whose hash differs from the plan's, and a material a site substituted
///   with its own model (provenance "model_hashes", "substituted_models");
/// - an analysis run that the plan does not name, one it names that was not run, a
///   sphericity correction other than the plan's;
/// - ratings or participants excluded by a rule the plan does not name, and a rule of the plan
///   that was not applied (`analyze --include-simulated`).

#include <string>

#include "hapticlab/replication/plan.hpp"

namespace hapticlab::db {
class Database;
struct Study;
}  // namespace hapticlab::db

namespace hapticlab::replication {

/// How analyze ran (its options that a plan fixes).
struct AnalyzeSettings {
  std::string correction;  ///< --correction; "" the protocol's
  bool include_simulated = false;
};

/// One deviation.
struct Deviation {
  std::string kind;  ///< e.g. "protocol key changed", "material substituted"
  std::string what;
};

/// Every deviation of study `st` in `d` from `plan`.
std::vector<Deviation> FindDeviations(const Plan& plan, const db::Database& d, const db::Study& st,
                                      const AnalyzeSettings& settings);

/// The report section (Markdown) of study `st`; a study other than the plan's says so.
std::string DeviationsSection(const Plan& plan, const db::Database& d, const db::Study& st,
                              const AnalyzeSettings& settings);

}  // namespace hapticlab::replication
