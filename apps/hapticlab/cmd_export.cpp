// hapticlab export: tidy CSV tables from a study database.

#include <fmt/core.h>

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/export.hpp"

namespace hapticlab::cli {

void RegisterExport(CLI::App& app) {
  struct Opts {
    std::string db, format = "csv", out;
    bool json = false, no_trajectories = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = app.add_subcommand(
      "export",
      "Write a study database as tidy long-format CSV tables (ratings, trials, events, one\n"
      "file per trajectory stream) that R's read.csv and pandas.read_csv read directly.\n"
      "A damaged database (SQLite quick_check) is refused; trajectories are those of each\n"
      "completed trial's completing attempt, checked against the sample counts stored at\n"
      "completion (a mismatch refuses the export, exit 2).");
  cmd->add_option("--db", o->db, "Study database (SQLite) to read")->required();
  cmd->add_option("--format", o->format, "Output format (only csv)")
      ->check(CLI::IsMember({"csv"}));
  cmd->add_option("--out", o->out, "Directory to write (created when missing)")->required();
  cmd->add_flag("--json", o->json, "Print the written files and row counts as JSON");
  cmd->add_flag("--no-trajectories", o->no_trajectories,
                "Only ratings, trials and events (trajectory CSVs can be hundreds of MB)");
  cmd->callback([o] {
    RunGuarded([&] {
      // quick_check first: a damaged record is refused, never exported.
      const db::Database database = db::OpenForReading(o->db);
      const auto files = db::ExportCsv(database, o->out, !o->no_trajectories);
      if (o->json) {
        nlohmann::json j = nlohmann::json::array();
        for (const auto& f : files) j.push_back({{"path", f.path}, {"rows", f.rows}});
        fmt::print("{}\n", nlohmann::json{{"files", j}}.dump(2));
      } else {
        for (const auto& f : files) fmt::print("{} ({} rows)\n", f.path, f.rows);
      }
      return kExitOk;
    });
  });
}

}  // namespace hapticlab::cli
