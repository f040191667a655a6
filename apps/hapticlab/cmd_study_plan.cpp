// hapticlab study freeze / verify / bundle / import: preregistered plans and replication
// bundles (replication/plan.hpp, bundle.hpp; docs/replication.md), and `study run --plan`.

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/replication/bundle.hpp"
#include "hapticlab/replication/plan.hpp"
#include "hapticlab/runner/open_rig.hpp"
#include "hapticlab/stats/long_table.hpp"
#include "study_plan.hpp"

namespace hapticlab::cli {
namespace {

using nlohmann::json;

void RegisterFreeze(CLI::App& study) {
  struct A {
    std::string protocol, participants = "8,12,16,20", exclusions = "simulated-ratings";
    replication::FreezeOptions o;
    bool no_power = false, quiet = false;
  };
  auto a = std::make_shared<A>();
  auto* cmd = study.add_subcommand(
      "freeze",
      "Freeze a study before data collection (preregistration): write a plan directory with\n"
      "the protocol and every file it names, its canonical form, every material model, a\n"
      "rig-file template, the analysis plan (analyses, correction, primary outcome, exclusion\n"
      "rules, the power analysis and its observer) and a SHA-256 manifest. Prints the plan\n"
      "hash (the SHA-256 of MANIFEST.sha256) to deposit with a registry (docs/replication.md).");
  cmd->add_option("PROTOCOL", a->protocol, "Study protocol (.toml)")->required();
  cmd->add_option("-o,--out", a->o.out_dir, "Plan directory (new, or empty)")->required();
  cmd->add_option("--rig-device", a->o.rig_device, "Device of the rig-file template")
      ->check(CLI::IsMember(runner::BackendNames()))
      ->capture_default_str();
  cmd->add_option("--primary-criterion", a->o.primary_criterion,
                  "Criterion of the primary outcome (default: overall, else the first)");
  cmd->add_option("--primary-effect", a->o.primary_effect,
                  "Effect of the primary outcome: method, material or method:material")
      ->capture_default_str();
  cmd->add_option("--alpha", a->o.alpha, "Significance level of the plan")->capture_default_str();
  cmd->add_option("--exclusions", a->exclusions,
                  "Exclusion rules, comma-separated, or 'none' (rules: simulated-ratings)")
      ->capture_default_str();
  cmd->add_flag("--no-power", a->no_power, "Write the plan without a power analysis");
  cmd->add_option("--observer", a->o.observer,
                  "Observer model of the power analysis, as 'study power --observer'");
  cmd->add_option("--power-participants", a->participants,
                  "Participant counts of the power "
                  "analysis")
      ->capture_default_str();
  cmd->add_option("--power-simulations", a->o.power_simulations, "Simulated studies per count")
      ->check(CLI::Range(1L, 1000000L))
      ->capture_default_str();
  cmd->add_option("--power-pool", a->o.power_pool, "Simulated participants through the runner")
      ->check(CLI::Range(1, 200))
      ->capture_default_str();
  cmd->add_option("--seed", a->o.power_seed, "Seed of the power simulations")
      ->capture_default_str();
  cmd->add_option("--threads", a->o.threads, "Worker threads")->check(CLI::Range(1, 256));
  cmd->add_flag("--quiet", a->quiet, "No progress on stderr");
  cmd->callback([a] {
    RunGuarded({{"out", "--out"},
                {"primary_criterion", "--primary-criterion"},
                {"primary_effect", "--primary-effect"},
                {"exclusions", "--exclusions"},
                {"alpha", "--alpha"}},
               [&] {
                 a->o.power = !a->no_power;
                 a->o.power_participants =
                     ParseParticipantCounts(a->participants, "--power-participants");
                 a->o.exclusions.clear();
                 if (a->exclusions != "none") a->o.exclusions = stats::SplitList(a->exclusions);
                 const auto hash = replication::FreezePlan(a->protocol, a->o, StderrLog(a->quiet));
                 fmt::print("plan {} written to {}\n", hash, a->o.out_dir);
                 return kExitOk;
               });
  });
}

void RegisterVerify(CLI::App& study) {
  struct A {
    std::string dir;
    bool json = false;
  };
  auto a = std::make_shared<A>();
  auto* cmd = study.add_subcommand(
      "verify",
      "Check a plan directory: every file against MANIFEST.sha256, the manifest against\n"
      "PLAN.sha256. Names every changed, missing or extra file; exit 2 when any.");
  cmd->add_option("PLAN", a->dir, "Plan directory")->required();
  cmd->add_flag("--json", a->json, "Print {plan_sha256, files, problems:[{path,kind,detail}]}");
  cmd->callback([a] {
    RunGuarded([&] {
      const auto v = replication::VerifyPlan(a->dir);
      if (a->json) {
        json ps = json::array();
        for (const auto& p : v.problems)
          ps.push_back({{"path", p.path}, {"kind", p.kind}, {"detail", p.detail}});
        PrintJson(json{{"plan_sha256", v.plan_hash}, {"files", v.files}, {"problems", ps}});
      } else if (v.ok()) {
        fmt::print("{}: ok — plan {}, {} files\n", a->dir, v.plan_hash, v.files);
      } else {
        fmt::print(stderr, "{}: the plan does not verify ({} problem{})\n{}", a->dir,
                   v.problems.size(), v.problems.size() == 1 ? "" : "s", v.Describe());
      }
      return v.ok() ? kExitOk : kExitBadInput;
    });
  });
}

void RegisterBundle(CLI::App& study) {
  struct A {
    std::string dir, out;
  };
  auto a = std::make_shared<A>();
  auto* cmd = study.add_subcommand(
      "bundle",
      "Pack a verified plan into one file for a replicating lab (a reproducible tar.gz; the\n"
      "plan hash travels inside). Read it with 'study import'.");
  cmd->add_option("PLAN", a->dir, "Plan directory")->required();
  cmd->add_option("-o,--out", a->out, "Bundle file (e.g. study.hlbundle)")->required();
  cmd->callback([a] {
    RunGuarded([&] {
      const auto hash = replication::WriteBundle(a->dir, a->out);
      fmt::print("bundle {} of plan {}\n", a->out, hash);
      return kExitOk;
    });
  });
}

void RegisterImport(CLI::App& study) {
  struct A {
    std::string bundle;
    replication::ImportOptions o;
    std::vector<std::string> substitutes;
  };
  auto a = std::make_shared<A>();
  auto* cmd = study.add_subcommand(
      "import",
      "Import a bundle at a replicating site: checks every hash (a bundle that does not match\n"
      "is refused, exit 2, naming the file), writes the plan, a site rig file to fill in\n"
      "(rig init / rig touch / rig calibrate) and site.toml with the site's own models. Then\n"
      "'study run --plan DIR'.");
  cmd->add_option("BUNDLE", a->bundle, "Bundle file")->required();
  cmd->add_option("--site", a->o.site,
                  "Pseudonymous site code recorded with every session run with --plan DIR\n"
                  "(up to 8 characters with a digit, e.g. S02; never a lab's name)")
      ->required();
  cmd->add_option("-o,--out", a->o.out_dir, "Site directory (new, or empty)")->required();
  cmd->add_option("--device", a->o.rig_device, "Device of the site's rig file")
      ->check(CLI::IsMember(runner::BackendNames()))
      ->capture_default_str();
  cmd->add_option("--substitute", a->substitutes,
                  "MATERIAL=MODEL.toml: the site's own model of a material (a deviation, "
                  "reported by analyze); repeatable");
  cmd->callback([a] {
    RunGuarded({{"site", "--site"}, {"out", "--out"}, {"substitute", "--substitute"}}, [&] {
      for (const auto& s : a->substitutes) {
        const auto eq = s.find('=');
        if (eq == std::string::npos || eq == 0 || eq + 1 == s.size())
          throw InputError(kCommandLine, 0, "--substitute",
                           "expected MATERIAL=MODEL.toml, got '" + s + "'");
        a->o.substitutes[s.substr(0, eq)] = s.substr(eq + 1);
      }
      const auto r = replication::ImportBundle(a->bundle, a->o);
      fmt::print(
          "site {}: plan {} ({} files) imported into {}; substituted: {}\n"
          "next: fill in {} (hapticlab rig init / rig touch / rig calibrate), "
          "then hapticlab study run --plan {} ...\n",
          a->o.site, r.plan_hash, r.files, a->o.out_dir,
          r.substituted.empty() ? std::string("none")
                                : fmt::format("{}", fmt::join(r.substituted, ", ")),
          (std::filesystem::path(a->o.out_dir) / "rig.toml").string(), a->o.out_dir);
      return kExitOk;
    });
  });
}

}  // namespace

protocols::Protocol LoadRunProtocol(const std::string& protocol, const std::string& plan,
                                    runner::RunOptions* o, bool quiet) {
  if (plan.empty()) {
    if (protocol.empty())
      throw InputError(kCommandLine, 0, "PROTOCOL", "missing (or give --plan PLAN)");
    return protocols::LoadProtocol(protocol);
  }
  auto run = replication::OpenPlanForRun(plan, protocol);
  o->plan_sha256 = run.plan.plan_hash;
  o->plan_site = run.site;
  o->plan_protocol_changes = run.changed_keys;
  o->model_files = run.model_files;
  if (!quiet) {
    fmt::print(stderr, "plan {} verified{}\n", run.plan.plan_hash,
               run.site.empty() ? "" : " (site " + run.site + ")");
    for (const auto& [material, file] : run.model_files)
      fmt::print(stderr, "deviation: {} rendered with the site's own model\n", material);
  }
  // A protocol given instead of the plan's: each changed key is a deviation (printed even
  // with --quiet; analyze --plan lists them again).
  for (const auto& c : run.changed_keys)
    fmt::print(stderr, "deviation: protocol key changed from the plan: {}\n", c);
  return std::move(run.protocol);
}

void RegisterStudyPreregistration(CLI::App& study) {
  RegisterFreeze(study);
  RegisterVerify(study);
  RegisterBundle(study);
  RegisterImport(study);
}

}  // namespace hapticlab::cli
