#pragma once
// Registration functions of the command groups (one file each).

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace hapticlab::cli {

void RegisterExport(CLI::App& app);
void RegisterModel(CLI::App& app);
void RegisterDemo(CLI::App& app);
void RegisterStats(CLI::App& app);
/// The stats commands (rm-anova, tukey, ...) as subcommands of `group`: `hapticlab stats`
/// and the lean `hapticlab-stats` binary share them.
void AddStatsCommands(CLI::App& group);
void RegisterStudy(CLI::App& app);
/// `study power` (cmd_power.cpp), registered under the study group.
void RegisterPower(CLI::App& study);
// "8,12,16": increasing participant counts 2..10000 (exit 2 naming `field` otherwise).
std::vector<int> ParseParticipantCounts(const std::string& s, const std::string& field);
/// `study calibrate` (cmd_calibrate.cpp), registered under the study group.
void RegisterCalibrate(CLI::App& study);
/// `study freeze`, `verify`, `bundle`, `import` (cmd_study_plan.cpp), under the study group.
void RegisterStudyPreregistration(CLI::App& study);
// study status (cmd_study_status.cpp).
void RegisterStudyStatus(CLI::App& study);
void RegisterAnalyze(CLI::App& app);
void RegisterWorkbench(CLI::App& app);
void RegisterDevice(CLI::App& app);
void RegisterParticipant(CLI::App& app);
void RegisterRig(CLI::App& app);
/// `rig init` and `rig touch` (cmd_rig_setup.cpp), registered under the rig group.
void RegisterRigSetup(CLI::App& rig);
void RegisterDb(CLI::App& app);

}  // namespace hapticlab::cli
