// hapticlab export: a study database as tidy CSV tables, a BIDS dataset or XDF files. One
// progress line per participant (stderr, --quiet drops them) and a summary at the end.

#include <fmt/core.h>

#include <chrono>
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
namespace {

struct ExportOpts {
  std::string db, format = "csv", out, participant;
  bool json = false, trajectories = false, no_trajectories = false, quiet = false;
};

std::string Megabytes(std::uintmax_t bytes) {
  return fmt::format("{:.1f} MB", static_cast<double>(bytes) / 1e6);
}

std::uintmax_t FileBytes(const std::string& path) {
  std::error_code ec;
  const auto n = std::filesystem::file_size(path, ec);
  return ec ? 0 : n;
}

// The summary line: what was written, where, how large, how long it took.
std::string Summary(const ExportOpts& o, const std::vector<db::ExportedFile>& files,
                    std::uintmax_t bytes, double seconds) {
  std::size_t rows = 0, streams = 0, samples = 0, tables = 0, physio = 0, physio_samples = 0;
  std::size_t beh = 0, beh_rows = 0;
  for (const auto& f : files) {
    rows += f.rows, streams += f.streams, samples += f.samples;
    if (f.path.ends_with(".csv") || f.path.ends_with(".tsv")) ++tables;
    if (f.path.ends_with("_beh.tsv")) ++beh, beh_rows += f.rows;
    if (f.path.ends_with("_physio.tsv.gz")) ++physio, physio_samples += f.rows;
  }
  std::string what;
  if (o.format == "xdf")
    what = fmt::format("{} XDF file{}, {} streams, {} samples", files.size(),
                       files.size() == 1 ? "" : "s", streams, samples);
  else if (o.format == "bids")
    what = fmt::format("{} files: {} rating tables ({} ratings), {} physio recordings ({} samples)",
                       files.size(), beh, beh_rows, physio, physio_samples);
  else
    what = fmt::format("{} tables, {} rows", tables, rows);
  return fmt::format("{} export of {}: {} -> {} ({}, {:.1f} s)", o.format, o.db, what, o.out,
                     Megabytes(bytes), seconds);
}

int RunExport(const ExportOpts& o) {
  if (!o.participant.empty() && o.format != "xdf")
    throw InputError(kCommandLine, 0, "--participant", "only --format xdf selects participants");
  if ((o.trajectories || o.no_trajectories) && o.format != "csv")
    throw InputError(kCommandLine, 0, o.trajectories ? "--trajectories" : "--no-trajectories",
                     "only --format csv chooses whether trajectories are written (BIDS and XDF "
                     "always hold them)");
  if (o.trajectories && o.no_trajectories)
    throw InputError(kCommandLine, 0, "--trajectories", "contradicts --no-trajectories");
  if (o.format != "xdf" && o.out.ends_with(".xdf"))
    throw InputError(o.out, 0, "--out", "a .xdf file name needs --format xdf");
  const auto start = std::chrono::steady_clock::now();
  const auto log = StderrLog(o.quiet || o.json);
  // quick_check first: a damaged record is refused, never exported.
  const db::Database database = db::OpenForReading(o.db);
  std::vector<db::ExportedFile> files;
  if (o.format == "bids") {
    files = db::ExportBids(database, o.out, log);
  } else if (o.format == "xdf") {
    files = db::ExportXdf(database, o.out, o.participant, log);
  } else {
    // The trajectory tables can be hundreds of MB: their size is said before either choice.
    const auto size = db::CountTrajectories(database);
    const std::string what = fmt::format("{} samples of {} streams, about {} as CSV", size.samples,
                                         size.streams, Megabytes(size.estimated_bytes));
    if (size.samples > 0)
      log(o.trajectories ? "writing trajectories: " + what
                         : "trajectories left out (" + what + "): --trajectories writes them");
    files = db::ExportCsv(database, o.out, o.trajectories, log);
  }
  std::uintmax_t bytes = 0;
  for (const auto& f : files) bytes += FileBytes(f.path);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (o.json) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& f : files) {
      nlohmann::json e{{"path", f.path}, {"bytes", FileBytes(f.path)}};
      if (o.format == "xdf")
        e.update({{"streams", f.streams}, {"samples", f.samples}});
      else
        e["rows"] = f.rows;
      j.push_back(e);
    }
    PrintJson(nlohmann::json{{"files", j}, {"bytes", bytes}, {"seconds", seconds}});
  } else {
    fmt::print("{}\n", Summary(o, files, bytes, seconds));
  }
  return kExitOk;
}

}  // namespace

void RegisterExport(CLI::App& app) {
  auto o = std::make_shared<ExportOpts>();
  auto* cmd = app.add_subcommand(
      "export",
      "Write a study database for other tools (docs/analysis.md shows how to load each):\n"
      "  csv   tidy long-format CSV tables (ratings, trials, events; with --trajectories one\n"
      "        file per trajectory stream) that R's read.csv and pandas.read_csv read\n"
      "        directly; --out DIR\n"
      "  bids  a BIDS dataset (ratings as beh/*_beh.tsv, force and vibration trajectories as\n"
      "        physio recordings with unit sidecars, protocol and models under code/) that the\n"
      "        official bids-validator accepts; --out DIR\n"
      "  xdf   XDF (Lab Streaming Layer) files, one per session: a stream per trajectory\n"
      "        stream plus event and rating marker streams on one clock; --out FILE.xdf (one\n"
      "        session: pick it with --participant) or --out DIR (one file per session)\n"
      "Prints one progress line per participant (stderr) and a summary of what was written.\n"
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
  cmd->add_flag("--trajectories", o->trajectories,
                "csv: also write the trajectories, one CSV per stream (their size is printed\n"
                "first: about 100 MB per participant recorded by the demo). Without it:\n"
                "ratings, trials and events only");
  // Kept for scripts written before trajectories became opt-in (issue #32): the default now.
  cmd->add_flag("--no-trajectories", o->no_trajectories, "")->group("");
  cmd->add_flag("--quiet", o->quiet, "No progress lines (the summary is still printed)");
  cmd->add_flag("--json", o->json,
                "Print the written files as JSON (rows per table; streams and samples per XDF "
                "file; bytes), no progress lines");
  cmd->callback([o] {
    RunGuarded({{"db", "--db"}, {"out", "--out"}, {"participant", "--participant"}},
               [&] { return RunExport(*o); });
  });
}

}  // namespace hapticlab::cli
