#pragma once
/// @file `hapticlab db merge`: the study databases of several rigs or sites combined into one
/// (docs/replication.md, "Combining sites").

#include <string>
#include <vector>

namespace hapticlab::db {

/// Conflicts a merge refuses unless allowed.
struct MergeOptions {
  /// One participant code at two sites (the same person at two sites, or two people whose
  /// codes collide): kept apart by their site-qualified codes.
  bool allow_shared_codes = false;
  /// Sessions recorded under different preregistered plans (provenance key "plan_sha256";
  /// a session without a plan counts as its own plan).
  bool allow_different_plans = false;
  /// One study name whose protocols differ (canonical SHA-256): the first input's protocol
  /// text is kept in the study row; each session keeps its own hash in its provenance.
  bool allow_different_protocols = false;
};

struct MergeSummary {
  std::vector<std::string> sites;  ///< site codes, sorted
  int participants = 0, sessions = 0, ratings = 0;
  /// Participants reserved with `participant new` but never run: not carried over.
  int reserved_left_out = 0;
};

/// A participant's code in a merged database: "SITE:CODE" ("S02:P07"), unless `code` is
/// already qualified (it holds ':', from an earlier merge).
std::string SiteQualifiedCode(const std::string& site, const std::string& code);

/// Merges `inputs` into a new file `output`. Each input is checked (SQLite quick_check) and
/// migrated forward when older (as `analyze` does); a newer one is refused. Participants
/// (with at least one session) get site-qualified codes; every session keeps its row
/// (site, rig hash, plan hash and software version in its provenance) and its trials,
/// ratings, events, trajectories and timing. Models and measurements are kept once per
/// content. Deterministic: the same inputs, in any order, give the same bytes (ids follow
/// site-qualified codes; nothing of the merge's time is stored). Atomic: the merge is built
/// in `output`.merging-build, compacted into `output`.merging (VACUUM INTO), synced and
/// linked to `output` only when whole; a killed merge leaves no `output` (the next run
/// replaces its leftovers).
/// @throws InputError (exit 2) naming both inputs for a conflict (the same file twice, a
///         participant in two inputs, a code at two sites, different plans or protocols
///         unless allowed), naming the file for a missing, damaged or newer input, or an
///         existing output
MergeSummary MergeDatabases(const std::vector<std::string>& inputs, const std::string& output,
                            const MergeOptions& options = {});

}  // namespace hapticlab::db
