// hapticlab export: a study database as tidy CSV tables, a BIDS dataset or XDF files.

#include <fmt/core.h>

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/export.hpp"
#include "hapticlab/db/interchange.hpp"

namespace hapticlab::cli {

void RegisterExport(CLI::App& app) {
  struct Opts {
    std::string db, format = "csv", out, participant;
    bool json = false, no_trajectories = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = app.add_subcommand(
      "export",
      "Write a study database for other tools (docs/analysis.md shows how to load each):\n"
      "  csv   tidy long-format CSV tables (ratings, trials, events, one file per trajectory\n"
      "        stream) that R's read.csv and pandas.read_csv read directly; --out DIR\n"
      "  bids  a BIDS dataset (ratings as beh/*_beh.tsv, force and vibration trajectories as\n"
      "        physio recordings with unit sidecars, protocol and models under code/) that the\n"
      "        official bids-validator accepts; --out DIR\n"
      "  xdf   XDF (Lab Streaming Layer) files, one per session: a stream per trajectory\n"
      "        stream plus event and rating marker streams on one clock; --out FILE.xdf (one\n"
      "        session: pick it with --participant) or --out DIR (one file per session)\n"
      "Only pseudonymous participant codes are written; no names or local paths.\n"
      "A damaged database (SQLite quick_check) is refused; trajectories are those of each\n"
      "completed trial's completing attempt, checked against the sample counts stored at\n"
      "completion (a mismatch refuses the export, exit 2).");
  cmd->add_option("--db", o->db, "Study database (SQLite) to read")->required();
  cmd->add_option("--format", o->format, "Output format: csv, bids or xdf")
      ->check(CLI::IsMember({"csv", "bids", "xdf"}))
      ->capture_default_str();
  cmd->add_option("--out", o->out,
                  "Directory to write (created when missing), or FILE.xdf for --format xdf")
      ->required();
  cmd->add_option("--participant", o->participant, "xdf: only this participant's sessions");
  cmd->add_flag("--json", o->json, "Print the written files and row (sample) counts as JSON");
  cmd->add_flag("--no-trajectories", o->no_trajectories,
                "csv: only ratings, trials and events (trajectory CSVs can be hundreds of MB)");
  cmd->callback([o] {
    RunGuarded({{"db", "--db"}, {"out", "--out"}, {"participant", "--participant"}}, [&] {
      if (!o->participant.empty() && o->format != "xdf")
        throw InputError(kCommandLine, 0, "--participant",
                         "only --format xdf selects participants");
      if (o->no_trajectories && o->format != "csv")
        throw InputError(kCommandLine, 0, "--no-trajectories",
                         "only --format csv leaves trajectories out");
      if (o->format != "xdf" && o->out.ends_with(".xdf"))
        throw InputError(o->out, 0, "--out", "a .xdf file name needs --format xdf");
      // quick_check first: a damaged record is refused, never exported.
      const db::Database database = db::OpenForReading(o->db);
      std::vector<db::ExportedFile> files;
      if (o->format == "bids")
        files = db::ExportBids(database, o->out);
      else if (o->format == "xdf")
        files = db::ExportXdf(database, o->out, o->participant);
      else
        files = db::ExportCsv(database, o->out, !o->no_trajectories);
      if (o->json) {
        nlohmann::json j = nlohmann::json::array();
        for (const auto& f : files) j.push_back({{"path", f.path}, {"rows", f.rows}});
        PrintJson(nlohmann::json{{"files", j}});
      } else {
        for (const auto& f : files) fmt::print("{} ({} rows)\n", f.path, f.rows);
      }
      return kExitOk;
    });
  });
}

}  // namespace hapticlab::cli
