#pragma once
// Registration functions of the command groups (one file each).

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace hapticlab::stats {
struct PsychometricPlot;
}

namespace hapticlab::cli {

void RegisterExport(CLI::App& app);
void RegisterModel(CLI::App& app);
void RegisterDemo(CLI::App& app);
/// Writes a psychometric figure to `<base>.svg` and `<base>.png` and returns their paths
/// (stats::DrawPsychometricPlot in the full CLI; none in hapticlab-stats, which links no
/// plotting library).
using PsychometricFigure =
    std::function<std::vector<std::string>(const stats::PsychometricPlot&, const std::string&)>;
/// `hapticlab stats`; `draw` as for AddStatsCommands.
void RegisterStats(CLI::App& app, const PsychometricFigure& draw = {});
/// The stats commands (rm-anova, tukey, ...) as subcommands of `group`: `hapticlab stats`
/// and the lean `hapticlab-stats` binary share them. `draw`: the figures of `psychometric`.
void AddStatsCommands(CLI::App& group, const PsychometricFigure& draw = {});
void RegisterStudy(CLI::App& app);
/// `study power` (cmd_power.cpp), registered under the study group.
void RegisterPower(CLI::App& study);
/// `study calibrate` (cmd_calibrate.cpp), registered under the study group.
void RegisterCalibrate(CLI::App& study);
void RegisterAnalyze(CLI::App& app);
void RegisterWorkbench(CLI::App& app);
void RegisterDevice(CLI::App& app);
void RegisterParticipant(CLI::App& app);
void RegisterRig(CLI::App& app);
void RegisterDb(CLI::App& app);

}  // namespace hapticlab::cli
