// hapticlab study: validate, plan, run, resume and inspect study protocols.

#include <fmt/core.h>

#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/study_runner.hpp"

namespace hapticlab::cli {
namespace {

using nlohmann::json;

runner::RecordMode ParseRecord(const std::string& s) {
  if (s == "none") return runner::RecordMode::kNone;
  if (s == "force") return runner::RecordMode::kForce;
  return runner::RecordMode::kAll;
}

void PrintSummary(const runner::RunSummary& s, bool json_out) {
  if (json_out) {
    fmt::print("{}\n", json{{"participant", s.participant}, {"session", s.session_id}, {"status", s.status},
                            {"planned", s.planned}, {"completed", s.completed}, {"executed", s.executed},
                            {"faults", s.faults}, {"simulated_s", s.simulated_s}, {"wall_s", s.wall_s}}
                           .dump(2));
  } else {
    fmt::print("{}: session {} {} — {}/{} trials completed, {} faults re-queued; {:.0f} s of stimuli in {:.1f} s\n",
               s.participant, s.session_id, s.status, s.completed, s.planned, s.faults, s.simulated_s, s.wall_s);
  }
}

}  // namespace

void RegisterStudy(CLI::App& app) {
  auto* study = app.add_subcommand("study", "Study protocols: validate, plan, run, resume, status (docs/studies.md)");
  study->require_subcommand(1);

  {
    auto path = std::make_shared<std::string>();
    auto* cmd = study->add_subcommand("validate", "Check a protocol; every problem is listed with file, line and key");
    cmd->add_option("PROTOCOL", *path, "Study protocol (.toml)")->required();
    cmd->callback([path] {
      RunGuarded([&] {
        const auto p = protocols::LoadProtocol(*path);
        int rated = 0;
        for (const auto& t : protocols::Plan(p, 0)) rated += t.rated;
        fmt::print("{}: ok — study '{}', {} materials, {} methods, {} criteria, {} rated trials per participant\n", *path,
                   p.name, p.materials.size(), p.methods.size(), p.criteria.size(), rated);
        return kExitOk;
      });
    });
  }
  {
    auto path = std::make_shared<std::string>();
    auto index = std::make_shared<int>(0);
    auto as_json = std::make_shared<bool>(false);
    auto* cmd = study->add_subcommand("plan", "Print a participant's exact trial list (deterministic from protocol, seed, index)");
    cmd->add_option("PROTOCOL", *path, "Study protocol (.toml)")->required();
    cmd->add_option("--participant", *index, "Participant index (0-based)")->capture_default_str()->check(CLI::NonNegativeNumber);
    cmd->add_flag("--json", *as_json, "Print the plan as JSON");
    cmd->callback([=] {
      RunGuarded([&] {
        const auto p = protocols::LoadProtocol(*path);
        const auto plan = protocols::Plan(p, *index);
        if (*as_json) {
          json j = json::array();
          for (const auto& t : plan)
            j.push_back({{"index", t.index}, {"phase", protocols::ToString(t.phase)}, {"material", t.material},
                         {"comparison", t.comparison}, {"method", t.method}, {"repetition", t.repetition},
                         {"left", t.left}, {"right", t.right}, {"rated", t.rated}, {"break_before", t.break_before}});
          fmt::print("{}\n", json{{"study", p.name}, {"participant_index", *index},
                                  {"participant_seed", protocols::ParticipantSeed(p, *index)}, {"trials", j}}.dump(2));
          return kExitOk;
        }
        fmt::print("study {} — participant index {} (seed {})\n", p.name, *index, protocols::ParticipantSeed(p, *index));
        fmt::print("{:>4}  {:<9} {:<16} {:<16} {:<10} {:>3}  {:<24} {:<24}\n", "#", "phase", "material", "comparison",
                   "method", "rep", "left", "right");
        for (const auto& t : plan) {
          if (t.break_before) fmt::print("      --- break ---\n");
          fmt::print("{:>4}  {:<9} {:<16} {:<16} {:<10} {:>3}  {:<24} {:<24}\n", t.index, protocols::ToString(t.phase),
                     t.material, t.comparison, t.method, t.repetition, t.left, t.right);
        }
        return kExitOk;
      });
    });
  }
  struct RunArgs {
    std::string protocol, db, participant, device = "sim", record = "all";
    int index = -1, stop_after = -1;
    double fault_rate = 0;
    bool ui = false, json = false, quiet = false;
  };
  {
    auto a = std::make_shared<RunArgs>();
    auto* cmd = study->add_subcommand(
        "run",
        "Run a new participant through the protocol and record everything to the database.\n"
        "Each trial's ratings commit in one transaction; after a crash use 'study resume'.");
    cmd->add_option("PROTOCOL", a->protocol, "Study protocol (.toml)")->required();
    cmd->add_option("--db", a->db, "Study database (created when missing)")->required();
    cmd->add_option("--participant", a->participant, "Pseudonymous participant code, e.g. P07")->required();
    cmd->add_option("--index", a->index, "Plan index of the participant (default: the next free one)");
    cmd->add_option("--device", a->device, "Device back-end")->check(CLI::IsMember({"sim", "falcon", "dhd", "openhaptics"}))
        ->capture_default_str();
    cmd->add_option("--record", a->record, "What to record per trial")->check(CLI::IsMember({"all", "force", "none"}))
        ->capture_default_str();
    cmd->add_option("--stop-after", a->stop_after, "Abort after this many trials (to test resume)");
    cmd->add_option("--inject-faults", a->fault_rate, "Sim: probability of a device fault per trial")
        ->check(CLI::Range(0.0, 0.9));
    cmd->add_flag("--ui", a->ui, "Participant and experimenter windows (issue #9; not in this build)");
    cmd->add_flag("--json", a->json, "Print the summary as JSON");
    cmd->add_flag("--quiet", a->quiet, "No per-trial progress");
    cmd->callback([a] {
      RunGuarded([&] {
        if (a->ui) throw InputError("", 0, "--ui", "the screens arrive with issue #9; run without --ui");
        const auto p = protocols::LoadProtocol(a->protocol);
        runner::RunOptions o;
        o.db_path = a->db;
        o.participant = a->participant;
        o.participant_index = a->index;
        o.device = a->device;
        o.record = ParseRecord(a->record);
        o.stop_after_trials = a->stop_after;
        o.fault_rate = a->fault_rate;
        if (!a->quiet && !a->json) o.log = [](const std::string& s) { fmt::print(stderr, "{}\n", s); };
        PrintSummary(runner::RunStudy(p, o), a->json);
        return kExitOk;
      });
    });
  }
  {
    auto a = std::make_shared<RunArgs>();
    auto* cmd = study->add_subcommand("resume", "Continue a participant's session where a crash or abort left it");
    cmd->add_option("--db", a->db, "Study database")->required();
    cmd->add_option("--participant", a->participant, "Participant code")->required();
    cmd->add_option("--record", a->record, "What to record per trial")->check(CLI::IsMember({"all", "force", "none"}))
        ->capture_default_str();
    cmd->add_option("--stop-after", a->stop_after, "Abort again after this many trials (tests)");
    cmd->add_flag("--json", a->json, "Print the summary as JSON");
    cmd->add_flag("--quiet", a->quiet, "No per-trial progress");
    cmd->callback([a] {
      RunGuarded([&] {
        runner::RunOptions o;
        o.db_path = a->db;
        o.participant = a->participant;
        o.record = ParseRecord(a->record);
        o.stop_after_trials = a->stop_after;
        if (!a->quiet && !a->json) o.log = [](const std::string& s) { fmt::print(stderr, "{}\n", s); };
        PrintSummary(runner::ResumeStudy(o), a->json);
        return kExitOk;
      });
    });
  }
  {
    auto a = std::make_shared<RunArgs>();
    auto* cmd = study->add_subcommand("status", "Progress of each participant: planned, completed, faulted, duplicates");
    cmd->add_option("--db", a->db, "Study database")->required();
    cmd->add_option("--participant", a->participant, "Only this participant");
    cmd->add_flag("--json", a->json, "Print {\"participants\":[{\"code\",\"planned\",\"completed\",\"faulted\",\"duplicates\"}]}");
    cmd->callback([a] {
      RunGuarded([&] {
        const auto st = runner::StudyStatus(a->db, a->participant);
        if (a->json) {
          json ps = json::array();
          for (const auto& s : st)
            ps.push_back({{"code", s.code}, {"planned", s.planned}, {"completed", s.completed}, {"faulted", s.faulted},
                          {"duplicates", s.duplicates}, {"session_status", s.session_status}});
          fmt::print("{}\n", json{{"participants", ps}}.dump(2));
        } else {
          fmt::print("{:<12} {:>8} {:>10} {:>8} {:>11}  {}\n", "participant", "planned", "completed", "faulted", "duplicates", "session");
          for (const auto& s : st)
            fmt::print("{:<12} {:>8} {:>10} {:>8} {:>11}  {}\n", s.code, s.planned, s.completed, s.faulted, s.duplicates,
                       s.session_status);
        }
        return kExitOk;
      });
    });
  }
}

}  // namespace hapticlab::cli
