#pragma once
/// @file Replication bundles (`hapticlab study bundle` / `study import`; docs/replication.md).
/// A bundle is a gzip-compressed POSIX tar (pax) of a plan directory, written by libarchive:
/// the plan's files in path order at the archive's top level, every entry a regular file with
/// mode 0644, owner 0:0, no user or group names and modification time 0, so the same plan
/// always gives the same bytes. The plan hash travels inside (PLAN.sha256).
///
/// A replicating site imports it into a site directory:
///
///   plan/                 the plan, every file checked against its manifest
///   site.toml             the site's code, the plan hash, the rig file, substituted models
///   rig.toml              the site's rig file to fill in (rig init / rig touch / rig calibrate)
///   site-models/<m>.toml  the site's own models of substituted materials
///
/// `study run --plan SITE_DIR` runs the plan with the substitutions; `analyze --plan` reports
/// each substitution as a deviation.

#include <map>
#include <string>
#include <vector>

#include "hapticlab/replication/plan.hpp"

namespace hapticlab::replication {

/// Packs the plan at `plan_dir` (verified first) into `out_path`. Returns the plan hash.
/// @throws InputError when the plan does not verify (every problem named)
std::string WriteBundle(const std::string& plan_dir, const std::string& out_path);

struct ImportOptions {
  std::string site;                   ///< pseudonymous site code, e.g. "S02" (CheckSiteCode)
  std::string out_dir;                ///< the site directory (created; must not exist or be empty)
  std::string rig_device = "falcon";  ///< the device of the site's rig-file template
  /// material id -> the site's own model file replacing the plan's
  std::map<std::string, std::string> substitutes;
};

struct ImportResult {
  std::string plan_hash;
  std::size_t files = 0;
  std::vector<std::string> substituted;  ///< material ids
};

/// Checks every entry of the bundle against the plan's manifest and hash, then writes the
/// site directory. @throws InputError naming the bundle and the entry whose hash differs (or
/// which is missing, extra, or unsafe: an absolute path, '..', a link), or the option at fault
ImportResult ImportBundle(const std::string& bundle_path, const ImportOptions& options);

/// A site code as `study run --site` and the database check it (db::SiteCodeProblem): up to 8
/// letters, digits, '-' or '_' with a digit, pseudonymous like participant codes (S02, never a
/// lab's name). @throws InputError naming `file` and `field` otherwise
void CheckSiteCode(const std::string& site, const std::string& field = "site",
                   const std::string& file = "<command line>");

/// What `study run --plan` runs: a plan directory or an imported site directory.
struct PlanRun {
  Plan plan;
  std::string site;  ///< "" for a plan directory
  /// material id -> model file replacing the plan's (the site's substitutions)
  std::map<std::string, std::string> model_files;
  protocols::Protocol protocol;  ///< the plan's protocol, or the one given instead
  /// The protocol keys that differ from the plan's (a protocol given instead of the plan's).
  std::vector<std::string> changed_keys;
};

/// Resolves `dir` (a plan, or a site directory holding site.toml), verifies the plan and
/// the site's substituted models, and loads the protocol: `protocol_path`, or the plan's
/// when empty. @throws InputError naming every file that does not verify
PlanRun OpenPlanForRun(const std::string& dir, const std::string& protocol_path);

}  // namespace hapticlab::replication
