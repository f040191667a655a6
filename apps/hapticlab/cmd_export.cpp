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
#include "hapticlab/db/export_formats.hpp"

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

// The formats' names, e.g. "csv, bids or xdf" (only those with `pred` true).
template <class Pred>
std::string FormatNames(Pred pred, const char* last = " or ") {
  std::vector<std::string> names;
  for (const auto& f : db::ExportFormats())
    if (pred(f)) names.push_back(f.name);
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i)
    s += (i == 0 ? "" : i + 1 == names.size() ? last : ", ") + names[i];
  return s;
}

// The options a format does not take are refused, naming the formats that take them.
void CheckOptions(const ExportOpts& o, const db::ExportFormat& f) {
  if (!o.participant.empty() && !f.selects_participants)
    throw InputError(kCommandLine, 0, "--participant",
                     "only --format " + FormatNames([](const auto& x) {
                       return x.selects_participants;
                     }) + " selects participants");
  if ((o.trajectories || o.no_trajectories) && !f.chooses_trajectories)
    throw InputError(
        kCommandLine, 0, o.trajectories ? "--trajectories" : "--no-trajectories",
        "only --format " + FormatNames([](const auto& x) { return x.chooses_trajectories; }) +
            " chooses whether trajectories are written (" +
            FormatNames([](const auto& x) { return !x.chooses_trajectories; }, " and ") +
            " always hold them)");
  if (o.trajectories && o.no_trajectories)
    throw InputError(kCommandLine, 0, "--trajectories", "contradicts --no-trajectories");
  const bool file_out = !f.file_extension.empty() && o.out.ends_with(f.file_extension);
  if (std::error_code ec;
      !file_out && std::filesystem::exists(o.out, ec) && !std::filesystem::is_directory(o.out, ec))
    throw InputError(o.out, 0, "--out", "exists and is not a folder: the export writes a folder");
  for (const auto& other : db::ExportFormats())
    if (&other != &f && !other.file_extension.empty() && o.out.ends_with(other.file_extension))
      throw InputError(
          o.out, 0, "--out",
          fmt::format("a {} file name needs --format {}", other.file_extension, other.name));
}

int RunExport(const ExportOpts& o) {
  const db::ExportFormat* format = db::FindExportFormat(o.format);
  if (!format)  // CLI11 checks the choices; kept for a format removed between the two
    throw InputError(kCommandLine, 0, "--format",
                     "expected " + FormatNames([](auto&) { return true; }));
  CheckOptions(o, *format);
  const auto start = std::chrono::steady_clock::now();
  // quick_check first: a damaged record is refused, never exported.
  const db::Database database = db::OpenForReading(o.db);
  const std::vector<db::ExportedFile> files =
      format->write(database, {.out = o.out,
                               .participant = o.participant,
                               .trajectories = o.trajectories,
                               .progress = StderrLog(o.quiet || o.json)});
  std::uintmax_t bytes = 0;
  for (const auto& f : files) bytes += FileBytes(f.path);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (o.json) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& f : files) {
      nlohmann::json e{{"path", f.path}, {"bytes", FileBytes(f.path)}};
      if (format->counts_streams)
        e.update({{"streams", f.streams}, {"samples", f.samples}});
      else
        e["rows"] = f.rows;
      j.push_back(e);
    }
    PrintJson(nlohmann::json{{"files", j}, {"bytes", bytes}, {"seconds", seconds}});
  } else {
    fmt::print("{} export of {}: {} -> {} ({}, {:.1f} s)\n", o.format, o.db,
               format->describe(files), o.out, Megabytes(bytes), seconds);
  }
  return kExitOk;
}

// The help of --format's choices: each format's name and its lines, indented.
std::string FormatsHelp() {
  std::string s;
  for (const auto& f : db::ExportFormats()) {
    s += fmt::format("  {:<6}", f.name);
    for (char c : f.help) s += c == '\n' ? std::string("\n        ") : std::string(1, c);
    s += "\n";
  }
  return s;
}

}  // namespace

void RegisterExport(CLI::App& app) {
  auto o = std::make_shared<ExportOpts>();
  auto* cmd = app.add_subcommand(
      "export",
      "Write a study database for other tools (docs/analysis.md shows how to load each):\n" +
          FormatsHelp() +
          "Prints one progress line per participant (stderr) and a summary of what was written.\n"
          "Only pseudonymous participant codes are written; no names or local paths.\n"
          "A damaged database (SQLite quick_check) is refused; trajectories are those of each\n"
          "completed trial's completing attempt, checked against the sample counts stored at\n"
          "completion (a mismatch refuses the export, exit 2).");
  cmd->add_option("--db", o->db, "Study database (SQLite) to read")->required();
  std::vector<std::string> names;
  for (const auto& f : db::ExportFormats()) names.push_back(f.name);
  cmd->add_option("--format", o->format,
                  "Output format: " + FormatNames([](auto&) { return true; }))
      ->check(CLI::IsMember(names))
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
