// hapticlab participant: pseudonymous participant codes by construction.

#include <fmt/core.h>

#include <filesystem>
#include <memory>
#include <set>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::cli {

void RegisterParticipant(CLI::App& app) {
  auto* part = app.add_subcommand(
      "participant", "Participant codes (pseudonymous by construction; docs/studies.md)");
  part->require_subcommand(1);
  struct O {
    std::string protocol, db, prefix = "P";
  };
  auto o = std::make_shared<O>();
  auto* cmd = part->add_subcommand(
      "new",
      "Print the next free participant code of a study: PREFIX and the lowest number (two\n"
      "digits or more) that matches the protocol's [study] participant_code pattern and is not\n"
      "yet in the database. Nothing is written; the code is taken when 'study run' uses it.");
  cmd->add_option("--protocol", o->protocol, "Study protocol (.toml)")->required();
  cmd->add_option("--db", o->db, "Study database (may not exist yet)")->required();
  cmd->add_option("--prefix", o->prefix, "Letters before the number")->capture_default_str();
  cmd->callback([o] {
    RunGuarded({{"db", "--db"}}, [&] {
      const auto p = protocols::LoadProtocol(o->protocol);
      std::set<std::string> taken;
      if (std::error_code ec; std::filesystem::exists(o->db, ec)) {
        const db::Database d = db::OpenForReading(o->db);
        if (const auto st = d.FindStudy(p.name))
          for (const auto& x : d.Participants(st->id)) taken.insert(x.code);
      }
      for (int n = 1; n <= 9999; ++n) {
        const std::string code = fmt::format("{}{:02d}", o->prefix, n);
        if (taken.count(code)) continue;
        try {
          protocols::CheckParticipantCode(p, code);
        } catch (const InputError&) {
          continue;
        }
        fmt::print("{}\n", code);
        return kExitOk;
      }
      throw InputError(o->protocol, 0, "--prefix",
                       "no free code '" + o->prefix +
                           "NN' matches the protocol's participant_code pattern " +
                           p.participant_code);
    });
  });
}

}  // namespace hapticlab::cli
