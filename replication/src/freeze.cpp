// hapticlab study freeze: the plan directory of a protocol (replication/plan.hpp).

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/toml_util.hpp"
#include "hapticlab/core/version.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/design/power_pool.hpp"
#include "hapticlab/protocols/canonical.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/replication/plan.hpp"
#include "hapticlab/runner/rig.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "hapticlab/stats/power.hpp"
#include "models_internal.hpp"
#include "plan_internal.hpp"

namespace hapticlab::replication {
namespace internal {

// A TOML basic string (JSON's escapes are TOML's; DEL is escaped as TOML requires).
std::string Quote(const std::string& s) {
  std::string j = nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::string out;
  for (const char c : j) out += c == '\x7f' ? std::string("\\u007F") : std::string(1, c);
  return out;
}

std::string RigTemplateText(const std::string& device, const std::string& whose) {
  return "# Rig-file template of " + whose + " (device '" + device +
         "'): frames and force calibration of the rig.\n"
         "# Fill it in for your own device: `hapticlab rig init --device DEVICE` explains the "
         "steps,\n"
         "# `hapticlab rig touch` records touched points, `hapticlab rig calibrate` writes the "
         "poses.\n"
         "# The poses below are the built-in rig's: placeholders until calibrated.\n\n" +
         runner::RigToToml(runner::DefaultRig(device));
}

}  // namespace internal
namespace {

using internal::kCommandLine;
using internal::Quote;

std::string QuoteList(const std::vector<std::string>& v) {
  std::vector<std::string> q;
  for (const auto& s : v) q.push_back(Quote(s));
  return "[" + fmt::format("{}", fmt::join(q, ", ")) + "]";
}

namespace fs = std::filesystem;
using Files = std::map<std::string, std::string>;

struct PowerSummary {
  std::string json, observer, observer_sha256;
  int needed = 0;
};

// The power analysis of the frozen protocol (read from the plan's copy, so that the observer
// it names is the plan's), as `study power` runs it.
PowerSummary RunPower(const protocols::Protocol& p, const FreezeOptions& o,
                      const std::string& plan_dir, const std::string& criterion,
                      const std::function<void(const std::string&)>& log) {
  const auto model = design::ChooseObserver(p, o.observer, "--observer");
  if (log) log("power: observer " + model.Describe() + "; recording the physics pool");
  const auto pool = design::RecordFeltPool(p, o.power_pool, o.threads, log);
  stats::PowerOptions po;
  po.participants = o.power_participants;
  po.simulations = o.power_simulations;
  po.seed = o.power_seed;
  po.threads = o.threads;
  po.alpha = o.alpha;
  const auto& obs = model.params;
  auto r = stats::SimulatePower(
      p.name,
      [&pool, &obs](int n, Rng& rng) { return design::SimulateRatings(pool, obs, n, rng, true); },
      po);
  PowerSummary s;
  // Named by its path inside the plan (a path outside it would carry a user's folder).
  std::error_code ec;
  s.observer = model.file.empty() ? std::string("built-in uncalibrated")
                                  : fs::weakly_canonical(model.file, ec)
                                        .lexically_relative(fs::weakly_canonical(plan_dir, ec))
                                        .generic_string();
  s.observer_sha256 = model.sha256;
  r.observer_file = model.file.empty() ? "" : s.observer;
  r.observer_sha256 = model.sha256;
  s.json = stats::PowerToJson(r);
  s.needed = stats::ParticipantsFor(r, criterion, o.primary_effect, o.power_target);
  return s;
}

std::string AnalysisPlanText(const protocols::Protocol& p, const std::string& protocol_file,
                             const FreezeOptions& o, const std::string& criterion,
                             const std::vector<internal::ModelText>& models,
                             const PowerSummary* power) {
  std::string t =
      "# HapticLab analysis plan (hapticlab study freeze; docs/replication.md): what will be\n"
      "# analysed, decided before data collection. `hapticlab analyze --plan` reads it back\n"
      "# and lists every deviation from it.\n\n[plan]\n";
  t += "study = " + Quote(p.name) + "\n";
  t += "protocol = " + Quote(protocol_file) + "\n";
  t += "protocol_canonical_sha256 = " + Quote(db::HashText(protocols::CanonicalForm(p))) + "\n";
  t += "software = " + Quote(std::string(kVersion) + "+" + kGitSha) + "\n";
  t += "\n[analysis]\n# The preregistered analyses (the protocol's [analysis] tests); any "
       "other is exploratory.\n";
  t += "tests = " + QuoteList(p.analyses) + "\n";
  t += "correction = " + Quote(p.correction) + "  # sphericity correction (afex's names)\n";
  t += "lmm_formula = " + Quote(p.lmm_formula) + "\n";
  t += fmt::format("alpha = {}\n", o.alpha);
  t += "primary_criterion = " + Quote(criterion) + "\n";
  t += "primary_effect = " + Quote(o.primary_effect) + "  # of the repeated-measures ANOVA\n";
  t += "# Exclusion rules the report applies (simulated-ratings: the simulated observer's\n"
       "# ratings are left out of a study that holds ratings by a person).\n";
  t += "exclusions = " + QuoteList(o.exclusions) + "\n";
  for (const auto& m : models)
    t += "\n[[model]]\nmaterial = " + Quote(m.material) + "\nfile = " + Quote(m.plan_file) +
         "\nsha256 = " + Quote(m.sha256) + "\nsource = " + Quote(m.source) + "\n";
  if (power) {
    t += "\n[power]\nfile = \"power.json\"\nobserver = " + Quote(power->observer) + "\n";
    if (!power->observer_sha256.empty())
      t += "observer_sha256 = " + Quote(power->observer_sha256) + "\n";
    t += fmt::format(
        "simulations = {}\nseed = {}\nparticipants = [{}]\ntarget = {}\n"
        "# The smallest count with power >= target for the primary outcome (0: none reached).\n"
        "participants_needed = {}\n",
        o.power_simulations, o.power_seed, fmt::join(o.power_participants, ", "), o.power_target,
        power->needed);
  }
  return t;
}

void CheckOptions(const protocols::Protocol& p, const FreezeOptions& o, std::string* criterion) {
  Diagnostics d;
  *criterion = o.primary_criterion;
  if (criterion->empty())
    *criterion = std::count(p.criteria.begin(), p.criteria.end(), "overall") ? "overall"
                 : p.criteria.empty()                                        ? ""
                                                                             : p.criteria.front();
  if (std::find(p.criteria.begin(), p.criteria.end(), *criterion) == p.criteria.end())
    d.Add(kCommandLine, 0, "primary_criterion",
          fmt::format("expected one of the protocol's criteria ({}), got '{}'",
                      fmt::join(p.criteria, ", "), *criterion));
  if (o.primary_effect != "method" && o.primary_effect != "material" &&
      o.primary_effect != "method:material")
    d.Add(kCommandLine, 0, "primary_effect",
          "expected method, material or method:material, got '" + o.primary_effect + "'");
  for (const auto& e : o.exclusions)
    if (e != kRuleSimulatedRatings)
      d.Add(kCommandLine, 0, "exclusions",
            fmt::format("unknown rule '{}' (rules: {})", e, kRuleSimulatedRatings));
  if (!(o.alpha > 0 && o.alpha < 1)) d.Add(kCommandLine, 0, "alpha", "expected 0 < alpha < 1");
  d.ThrowIfAny();
}

}  // namespace

std::string FreezePlan(const std::string& protocol_path, const FreezeOptions& o,
                       const std::function<void(const std::string&)>& log) {
  internal::CheckEmptyOutput(o.out_dir, "out");
  const auto p = protocols::LoadProtocol(protocol_path);
  std::string criterion;
  CheckOptions(p, o, &criterion);
  // The protocol and every file it names, then every model (built from the original folder).
  Files files = internal::ProtocolFiles(p);
  const auto models = internal::ModelsOf(p);
  const std::string protocol_file = "protocol/" + fs::path(p.file).filename().string();
  // Written to a sibling folder first and renamed at the end: a failed freeze leaves no plan.
  fs::path out = fs::path(o.out_dir).lexically_normal();
  if (!out.has_filename()) out = out.parent_path();  // "PLAN/"
  const fs::path tmp = out.parent_path() / (out.filename().string() + ".freezing");
  std::error_code ec;
  fs::remove_all(tmp, ec);
  struct RemoveUnlessKept {  // however the freeze fails, no partial plan stays behind
    fs::path dir;
    bool keep = false;
    ~RemoveUnlessKept() {
      std::error_code e;
      if (!keep) fs::remove_all(dir, e);
    }
  } guard{tmp};
  internal::WriteTree(tmp.string(), files);
  // The copy must load and give every model the same hash: it is what sites will run.
  const auto copy = protocols::LoadProtocol((tmp / protocol_file).string());
  const auto copied = internal::ModelsOf(copy);
  for (std::size_t i = 0; i < models.size(); ++i)
    if (copied[i].sha256 != models[i].sha256)
      throw InputError(protocol_path, 0, "material.model",
                       "material '" + models[i].material +
                           "': its model loads differently from the plan's copy (a file it "
                           "names is missing there)");
  for (const auto& m : models) files[m.plan_file] = m.text;
  files["protocol.canonical.json"] = protocols::CanonicalForm(p);
  files["rig-template.toml"] = internal::RigTemplateText(o.rig_device, "this plan");
  PowerSummary power;
  if (o.power) {
    if (!o.observer.empty() && o.observer != "builtin") {
      files["power-observer.toml"] = ReadTextFile(o.observer, "observer file");
      WriteTextFile((tmp / "power-observer.toml").string(), files["power-observer.toml"]);
    }
    FreezeOptions po = o;
    if (files.count("power-observer.toml")) po.observer = (tmp / "power-observer.toml").string();
    power = RunPower(copy, po, tmp.string(), criterion, log);
    // The observer as named inside the final plan.
    files["power.json"] = power.json;
  }
  files[kAnalysisPlanFile] =
      AnalysisPlanText(p, protocol_file, o, criterion, models, o.power ? &power : nullptr);
  const std::string manifest = internal::ManifestText(files);
  std::string plan_hash = db::HashText(manifest);
  files[kManifestFile] = manifest;
  files[kPlanHashFile] = plan_hash + "  " + kManifestFile + "\n";
  internal::WriteTree(tmp.string(), files);
  fs::remove(out, ec);  // an empty directory, checked above
  fs::rename(tmp, out);
  guard.keep = true;
  return plan_hash;
}

}  // namespace hapticlab::replication
