// hapticlab study status: each participant's progress (split from cmd_study.cpp).
#include <fmt/core.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/runner/study_runner.hpp"

namespace hapticlab::cli {

using nlohmann::json;

void RegisterStudyStatus(CLI::App& study) {
  struct StatusArgs {
    std::string db, participant;
    bool json = false;
  };
  auto a = std::make_shared<StatusArgs>();
  auto* cmd = study.add_subcommand(
      "status",
      "Progress of each participant: planned, completed, faulted (attempts, each re-queued),\n"
      "duplicates, session status (running, completed, aborted, failed; a run that was killed\n"
      "or crashed stays 'running' until 'study resume' continues it; reserved: a code from\n"
      "'participant new' with no session yet)");
  cmd->add_option("--db", a->db, "Study database")->required();
  cmd->add_option("--participant", a->participant, "Only this participant");
  cmd->add_flag("--json", a->json,
                "Print "
                "{\"participants\":[{\"code\",\"planned\",\"completed\",\"faulted\",\"duplicates\","
                "\"session_status\"}]}");
  cmd->callback([a] {
    RunGuarded({{"participant", "--participant"}, {"db", "--db"}}, [&] {
      const auto st = runner::StudyStatus(a->db, a->participant);
      // A code reserved by `participant new` has no session yet.
      const auto status = [](const runner::ParticipantStatus& s) {
        return s.session_status ? std::string(NameOf(db::kSessionStatusNames, *s.session_status))
                                : std::string("reserved");
      };
      if (a->json) {
        json ps = json::array();
        for (const auto& s : st)
          ps.push_back({{"code", s.code},
                        {"planned", s.planned},
                        {"completed", s.completed},
                        {"faulted", s.faulted},
                        {"duplicates", s.duplicates},
                        {"session_status", status(s)}});
        PrintJson(json{{"participants", ps}});
      } else {
        fmt::print("{:<12} {:>8} {:>10} {:>8} {:>11}  {}\n", "participant", "planned", "completed",
                   "faulted", "duplicates", "session");
        for (const auto& s : st)
          fmt::print("{:<12} {:>8} {:>10} {:>8} {:>11}  {}\n", s.code, s.planned, s.completed,
                     s.faulted, s.duplicates, status(s));
      }
      return kExitOk;
    });
  });
}

}  // namespace hapticlab::cli
