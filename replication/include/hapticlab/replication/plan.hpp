#pragma once
/// @file Preregistered study plans (`hapticlab study freeze` / `study verify`;
/// docs/replication.md). A plan is a directory that holds everything decided before data
/// collection:
///
///   protocol/<file>           the protocol exactly as given, and every file it names
///                             (profiles, observer, model files) at the same relative paths
///   protocol.canonical.json   its canonical form (protocols/canonical.hpp)
///   models/<material>.toml    every material model the protocol uses (placeholders built)
///   rig-template.toml         a rig file to fill in (`rig init` / `rig touch` / `rig calibrate`)
///   analysis-plan.toml        analyses, correction, primary outcome, exclusion rules, models,
///                             the power analysis and its observer
///   power.json                the power analysis (`study power`'s JSON), unless --no-power
///   MANIFEST.sha256           one line per file above: "<sha256 hex>  <path>", sorted by path
///                             (byte order), '/' separators: the format `sha256sum -c` reads
///   PLAN.sha256               "<plan hash>  MANIFEST.sha256"
///
/// The plan hash is the SHA-256 of the bytes of MANIFEST.sha256. It changes exactly when a
/// file's content, a file's path, or the set of files changes; `sha256sum -c PLAN.sha256` and
/// `sha256sum -c MANIFEST.sha256` (GNU coreutils) check a plan without HapticLab.

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::replication {

inline constexpr const char* kManifestFile = "MANIFEST.sha256";
inline constexpr const char* kPlanHashFile = "PLAN.sha256";
inline constexpr const char* kAnalysisPlanFile = "analysis-plan.toml";
/// The exclusion rules the report applies (stats/report.hpp), by name.
inline constexpr const char* kRuleSimulatedRatings = "simulated-ratings";

/// What `study freeze` asks for besides the protocol.
struct FreezeOptions {
  std::string out_dir;                ///< created; must not exist or be empty
  std::string rig_device = "falcon";  ///< the device of the rig-file template
  /// The primary outcome: a criterion of the protocol (default "overall" when it has one,
  /// else its first) and an effect of the repeated-measures ANOVA.
  std::string primary_criterion, primary_effect = "method";
  double alpha = 0.05;
  std::vector<std::string> exclusions{kRuleSimulatedRatings};
  // The power analysis (design/power_pool.hpp, stats/power.hpp), unless `power` is false.
  bool power = true;
  std::string observer;  ///< "" the protocol's observer, "builtin", or an observer file
  std::vector<int> power_participants{8, 12, 16, 20};
  long power_simulations = 200;
  int power_pool = 4, threads = 2;
  std::uint64_t power_seed = 1;
  double power_target = 0.8;
};

/// One problem `VerifyPlan` found.
struct PlanProblem {
  std::string path;    ///< the file, relative to the plan directory
  std::string kind;    ///< "changed", "missing", "extra", "malformed"
  std::string detail;  ///< what differs
};

struct VerifyResult {
  std::string plan_hash;  ///< SHA-256 of MANIFEST.sha256 as found
  std::size_t files = 0;  ///< files the manifest lists
  std::vector<PlanProblem> problems;
  bool ok() const { return problems.empty(); }
  /// One line per problem: "changed: protocol/small.toml (sha256 ... , manifest ...)".
  std::string Describe() const;
};

/// A material model of the plan.
struct PlanModel {
  std::string material, file, sha256, source;
};

/// The analysis plan as read back (analysis-plan.toml).
struct AnalysisPlan {
  std::string study, protocol_file, protocol_canonical_sha256, software;
  std::vector<std::string> tests, exclusions;
  std::string correction, lmm_formula, primary_criterion, primary_effect;
  double alpha = 0.05;
  std::vector<PlanModel> models;
  bool power = false;
  std::string power_observer, power_observer_sha256;
  int power_participants_needed = 0;
};

/// A verified plan, read.
struct Plan {
  std::string dir;        ///< the plan directory
  std::string plan_hash;  ///< SHA-256 of MANIFEST.sha256
  AnalysisPlan analysis;
  std::string protocol_path;  ///< dir/analysis.protocol_file
  std::string protocol_text;  ///< its bytes
};

/// Writes the plan of the protocol at `protocol_path` (docs/replication.md). Returns the
/// plan hash. `log` gets progress lines (the power analysis takes seconds to minutes).
/// @throws InputError when the protocol is invalid, names a file outside its folder, the
///         out directory is not empty, or an option does not fit the protocol
std::string FreezePlan(const std::string& protocol_path, const FreezeOptions& options,
                       const std::function<void(const std::string&)>& log = {});

/// Checks every file of a plan directory against its manifest and the plan hash.
VerifyResult VerifyPlan(const std::string& dir);

/// VerifyPlan, then reads the analysis plan. @throws InputError naming every problem.
Plan ReadPlan(const std::string& dir);

/// The checks of VerifyPlan on files in memory (path -> bytes; a bundle's entries).
VerifyResult VerifyFiles(const std::map<std::string, std::string>& files);

/// Parses analysis-plan.toml's text; `file` names it in errors. @throws InputError
AnalysisPlan ParseAnalysisPlan(const std::string& text, const std::string& file);

}  // namespace hapticlab::replication
