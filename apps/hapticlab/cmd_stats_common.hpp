#pragma once
// Pieces shared by the `stats` subcommands (cmd_stats.cpp, cmd_stats_lmm.cpp): the options
// every one of them takes and the CSV loading they apply.

#include <CLI/CLI.hpp>
#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "hapticlab/stats/long_table.hpp"
#include "stats_commands.hpp"

namespace hapticlab::cli::stats_cmd {

// NaN (undefined statistics) becomes JSON null.
inline nlohmann::json Num(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

// Options every stats subcommand shares.
struct Common {
  std::string csv, dv;
  std::vector<std::string> where;  // COL=VALUE
  std::string average_by;          // COLS
  bool json = false;
  bool allow_missing = false;      // rm-anova/tukey --within: --missing drop-subject
  bool include_simulated = false;  // keep source=simulated rows next to a person's ratings
};

/// --csv, --dv, --where, --average-by, --json, --include-simulated.
void AddCommon(CLI::App* cmd, Common& c);

/// Reads the CSV with the needed key columns, applies --where and --average-by.
stats::LongTable Load(const Common& c, std::vector<std::string> keys);

/// Refuses (InputError, exit 2) a result with a statistic that is not finite, naming the
/// response column and its most extreme row (file line) and saying why: a response that does
/// not vary, values whose squares overflow or underflow double precision, or an exact fit.
/// `values`: (name, value) of every statistic the command prints.
void RequireFinite(const stats::LongTable& t,
                   const std::vector<std::pair<std::string, double>>& values);

/// Runs `fit`; a numeric library's failure on the data (Boost.Math's domain, overflow or
/// evaluation errors, which would print library text) becomes the same refusal as
/// RequireFinite's, naming the column and row.
void Fitted(const stats::LongTable& t, const std::function<void()>& fit);

/// `stats lmm`.
void AddLmm(CLI::App& s);

/// `stats psychometric` (cmd_stats_psychometric.cpp); `draw` writes its figures (empty in the
/// lean hapticlab-stats, which links no plotting library).
void AddPsychometric(CLI::App& s, PsychometricFigure draw);

}  // namespace hapticlab::cli::stats_cmd
