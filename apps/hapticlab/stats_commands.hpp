#pragma once
// The stats command group with the psychometric figures: the full CLI passes a drawer, the
// lean hapticlab-stats none (commands.hpp's RegisterStats / AddStatsCommands: no figures).

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace hapticlab::stats {
struct PsychometricPlot;
}

namespace hapticlab::cli {

/// Writes a psychometric figure to `<base>.svg` and `<base>.png` and returns their paths
/// (stats::DrawPsychometricPlot in the full CLI; none in hapticlab-stats, which links no
/// plotting library).
using PsychometricFigure =
    std::function<std::vector<std::string>(const stats::PsychometricPlot&, const std::string&)>;

/// `hapticlab stats` whose `psychometric --figure` draws with `draw`.
void RegisterStats(CLI::App& app, const PsychometricFigure& draw);
/// The stats commands as subcommands of `group`; `draw`: the figures of `psychometric`.
void AddStatsCommands(CLI::App& group, const PsychometricFigure& draw);

}  // namespace hapticlab::cli
