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

/// Why the vibration channel of `model` (read from `path`) is not scored on `r`, or "" when it
/// is (or the measurement has no acceleration): compare and diagnose score the workbench's band
/// model only, and a renderer AR bank (`model fit-vibration`) or neural model is refused
/// explicitly instead of being dropped without a word (issue #33).
std::string VibrationNotScored(const std::string& path, const modeling::wb::Model& model,
                               const modeling::wb::Replay& r);

void AddFit(CLI::App& app);
void AddCompare(CLI::App& app);
void AddDiagnose(CLI::App& app);

}  // namespace hapticlab::cli::workbench_cli
