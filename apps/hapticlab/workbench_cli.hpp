#pragma once
// Shared by the workbench sub-commands (cmd_workbench*.cpp): JSON and text forms of errors and
// fit reports, measurement loading, progress lines.

#include <CLI/CLI.hpp>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::cli::workbench_cli {

nlohmann::json ErrorsJson(const modeling::wb::Errors& e);
std::string ErrorsLine(const modeling::wb::Errors& e);
/// Reads a measurement CSV and prepares it for replay (in the model's vibration bands).
/// `measurement` read and prepared for replay (with `model`'s vibration bands when it has
/// them); `keep`: the measurement as read, and `options`: how it was replayed.
modeling::wb::Replay Load(const std::string& measurement, const modeling::wb::Model* model,
                          Measurement* keep = nullptr,
                          modeling::wb::ReplayOptions* options = nullptr);

// ---------------------------------------------------------------------------------------------
// Progress lines on stderr (a person waits on fits of a minute); --quiet silences them.
struct Progress {
  bool quiet = false;
  std::mutex mu;
  void Line(const std::string& s) {
    if (quiet) return;
    std::lock_guard<std::mutex> lock(mu);
    fmt::print(stderr, "{}\n", s);
    std::fflush(stderr);
  }
};

nlohmann::json FitReportJson(const modeling::wb::FitReport& rep);

/// When the model read from `path` has no band model and its material's vibration is an AR
/// bank (`model fit-vibration`, an imported Penn model) or a neural model, attaches it to
/// `model` (modeling/workbench_vibration.hpp) so that compare and diagnose score it by E_s, and
/// returns a line saying what is scored (issue #33); else "".
std::string AttachVibration(const std::string& path, modeling::wb::Model* model);
/// The per-condition E_s table (speed x force) as JSON rows.
nlohmann::json EsCellsJson(const std::vector<modeling::wb::EsCell>& cells);
/// ... and as text lines (none when `cells` is empty).
void PrintEsCells(const std::string& title, const std::vector<modeling::wb::EsCell>& cells);

void AddFit(CLI::App& app);
void AddCompare(CLI::App& app);
void AddDiagnose(CLI::App& app);

}  // namespace hapticlab::cli::workbench_cli
