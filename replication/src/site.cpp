// A replicating site: importing a bundle into a site directory, and opening a plan or a site
// directory for `study run --plan` (replication/bundle.hpp).

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/canonical.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/replication/bundle.hpp"
#include "plan_internal.hpp"

namespace hapticlab::replication {
namespace {

namespace fs = std::filesystem;
constexpr const char* kSiteFile = "site.toml";
using internal::kCommandLine;

// The site's substitutions, checked and copied: material -> (file in the site dir, bytes).
std::map<std::string, std::pair<std::string, std::string>> Substitutes(const AnalysisPlan& plan,
                                                                       const ImportOptions& o) {
  Diagnostics d;
  std::map<std::string, std::pair<std::string, std::string>> out;
  std::vector<std::string> materials;
  for (const auto& m : plan.models) materials.push_back(m.material);
  for (const auto& [material, path] : o.substitutes) {
    if (std::find(materials.begin(), materials.end(), material) == materials.end()) {
      d.Add(kCommandLine, 0, "substitute",
            fmt::format("no material '{}' in the plan (its materials: {})", material,
                        fmt::join(materials, ", ")));
      continue;
    }
    try {
      const auto model = renderer::LoadMaterial(path);
      const auto doc = ParseTomlFile(path, "model");
      const bool self_contained =
          model.neural_file.empty() && !doc["geometry"]["file"] && !doc["vibration"]["file"];
      if (!self_contained)
        d.Add(path, 0, "substitute",
              "a substituted model is copied into the site directory alone: give a model whose "
              "geometry and vibration are in the file itself (it names other files)");
      out[material] = {"site-models/" + internal::SafeName(material) + ".toml",
                       ReadTextFile(path, "model")};
    } catch (const InputError& e) {
      for (const auto& x : e.diagnostics()) d.Add(x.file, x.line, x.field, x.message);
    }
  }
  d.ThrowIfAny();
  return out;
}

std::string SiteText(const ImportOptions& o, const std::string& plan_hash, const AnalysisPlan& plan,
                     const std::map<std::string, std::pair<std::string, std::string>>& subs) {
  using internal::Quote;
  std::string t =
      "# Site file of a replication (hapticlab study import; docs/replication.md).\n"
      "# `hapticlab study run --plan THIS_FOLDER` runs the plan below with these models.\n\n"
      "[site]\ncode = " +
      Quote(o.site) + "\nplan = \"plan\"\nplan_sha256 = " + Quote(plan_hash) +
      "\nrig = \"rig.toml\"\ndevice = " + Quote(o.rig_device) + "\n";
  for (const auto& [material, fb] : subs) {
    std::string planned;
    for (const auto& m : plan.models)
      if (m.material == material) planned = m.sha256;
    t += "\n# The site's own model of " + material + " replaces the plan's (a deviation).\n";
    t += "[[substitution]]\nmaterial = " + Quote(material) + "\nfile = " + Quote(fb.first) +
         "\nsha256 = " + Quote(db::HashText(fb.second)) +
         "\nplan_model_sha256 = " + Quote(planned) + "\n";
  }
  return t;
}

}  // namespace

void CheckSiteCode(const std::string& site, const std::string& field, const std::string& file) {
  if (const std::string why = db::SiteCodeProblem(site); !why.empty())
    throw InputError(file, 0, field,
                     "'" + site + "' is not a site code (" + why +
                         "): up to 8 letters, digits, '-' or '_' with a digit, e.g. S02");
}

ImportResult ImportBundle(const std::string& bundle_path, const ImportOptions& o) {
  CheckSiteCode(o.site);
  internal::CheckEmptyOutput(o.out_dir, "out");
  const auto files = internal::ReadArchive(bundle_path);
  const auto v = VerifyFiles(files);
  if (!v.ok()) {
    Diagnostics d;
    for (const auto& p : v.problems)
      d.Add(bundle_path, 0, p.path, p.kind + " (" + p.detail + "): the bundle is refused");
    d.ThrowIfAny();
  }
  const auto plan =
      ParseAnalysisPlan(files.at(kAnalysisPlanFile), bundle_path + ":" + kAnalysisPlanFile);
  const auto subs = Substitutes(plan, o);
  std::map<std::string, std::string> site;
  for (const auto& [path, bytes] : files) site["plan/" + path] = bytes;
  for (const auto& [material, fb] : subs) site[fb.first] = fb.second;
  site["rig.toml"] = internal::RigTemplateText(o.rig_device, "site " + o.site);
  site[kSiteFile] = SiteText(o, v.plan_hash, plan, subs);
  internal::WriteTree(o.out_dir, site);
  ImportResult r{.plan_hash = v.plan_hash, .files = v.files, .substituted = {}};
  for (const auto& [material, fb] : subs) r.substituted.push_back(material);
  return r;
}

PlanRun OpenPlanForRun(const std::string& dir, const std::string& protocol_path) {
  PlanRun run;
  std::string plan_dir = dir;
  const fs::path site_file = fs::path(dir) / kSiteFile;
  std::error_code ec;
  if (fs::is_regular_file(site_file, ec)) {
    const auto doc = ParseTomlFile(site_file.string(), "site file");
    run.site = doc["site"]["code"].value_or(std::string());
    CheckSiteCode(run.site, "site.code", site_file.string());
    plan_dir = (fs::path(dir) / doc["site"]["plan"].value_or(std::string("plan"))).string();
    run.plan = ReadPlan(plan_dir);
    if (doc["site"]["plan_sha256"].value_or(std::string()) != run.plan.plan_hash)
      throw InputError(site_file.string(), 0, "site.plan_sha256",
                       "the plan in " + plan_dir + " is not the one imported (plan hash " +
                           run.plan.plan_hash + ")");
    Diagnostics d;
    if (const auto* subs = doc["substitution"].as_array())
      for (const auto& node : *subs) {
        const auto* s = node.as_table();
        if (!s) continue;
        const std::string material = (*s)["material"].value_or(std::string());
        const std::string file = (*s)["file"].value_or(std::string());
        const fs::path path = fs::path(dir) / file;
        if (!internal::SafeRelativePath(file) || !fs::is_regular_file(path, ec)) {
          d.Add(site_file.string(), 0, "substitution.file", "no model file '" + file + "'");
          continue;
        }
        if (db::HashText(ReadTextFile(path.string())) != (*s)["sha256"].value_or(std::string()))
          d.Add(path.string(), 0, "sha256",
                "changed since the import (its SHA-256 differs from site.toml's)");
        run.model_files[material] = fs::absolute(path).lexically_normal().string();
      }
    d.ThrowIfAny();
  } else {
    run.plan = ReadPlan(plan_dir);
  }
  run.protocol =
      protocols::LoadProtocol(protocol_path.empty() ? run.plan.protocol_path : protocol_path);
  if (!protocol_path.empty())
    for (const auto& c : protocols::CanonicalDifferences(run.plan.protocol_text, run.protocol.text))
      run.changed_keys.push_back(c.Describe());
  return run;
}

}  // namespace hapticlab::replication
