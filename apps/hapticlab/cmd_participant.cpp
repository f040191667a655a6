// hapticlab participant: pseudonymous participant codes by construction.

#include <fmt/core.h>

#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/study_record.hpp"

namespace hapticlab::cli {

void RegisterParticipant(CLI::App& app) {
  auto* part = app.add_subcommand(
      "participant", "Participant codes (pseudonymous by construction; docs/studies.md)");
  part->require_subcommand(1);
  struct O {
    std::string protocol, db, prefix;
  };
  auto o = std::make_shared<O>();
  auto* cmd = part->add_subcommand(
      "new",
      "Reserve and print the next free participant code of a study: a prefix and the lowest\n"
      "number that matches the protocol's [study] participant_code pattern and is not yet in\n"
      "the database (e.g. P01 for the default pattern, NU001 for \"^NU[0-9]{3}$\"). The code is\n"
      "stored as reserved (with its plan index) in the database, created when missing, so two\n"
      "calls never return the same code; 'study status' lists it as reserved and 'study run\n"
      "--participant CODE' runs it. The protocol must be the one the database's study was run\n"
      "with (compared by content; comments and formatting do not count).");
  cmd->add_option("--protocol", o->protocol, "Study protocol (.toml)")->required();
  cmd->add_option("--db", o->db, "Study database (created when missing)")->required();
  cmd->add_option("--prefix", o->prefix,
                  "Letters before the number (default: the pattern's fixed start, else P)");
  cmd->callback([o] {
    RunGuarded({{"db", "--db"}, {"study", "--db"}}, [&] {
      const auto p = protocols::LoadProtocol(o->protocol);
      fmt::print("{}\n", runner::ReserveParticipant(o->db, p, o->prefix).code);
      return kExitOk;
    });
  });
}

}  // namespace hapticlab::cli
