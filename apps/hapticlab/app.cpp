#include "app.hpp"

#include <fmt/core.h>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/version.hpp"
#include "hapticlab/stats/psychometric_report.hpp"
#include "stats_commands.hpp"

namespace hapticlab::cli {

void BuildApp(CLI::App& app) {
  app.description(
      "HapticLab: model real textures, render them on a force-feedback device plus a\n"
      "vibrotactile actuator, run psychophysical studies comparing real and virtual\n"
      "textures, and analyse the ratings. Run 'hapticlab COMMAND --help' for details.\n"
      "Exit codes: 0 ok, 1 the work failed, 2 bad usage or bad input (the message names the\n"
      "file, line and field), 3 'study run'/'study resume' stopped before the session's end\n"
      "(what was completed is recorded; 'study resume' continues it).");
  app.name("hapticlab");
  app.set_version_flag("--version", fmt::format("hapticlab {} ({})", kVersion, kGitSha));
  app.require_subcommand(1);

  RegisterExport(app);
  RegisterModel(app);
  RegisterDemo(app);
  RegisterStats(app, stats::DrawPsychometricPlot);
  RegisterStudy(app);
  RegisterAnalyze(app);
  RegisterWorkbench(app);
  RegisterDevice(app);
  RegisterParticipant(app);
  RegisterRig(app);
  RegisterDb(app);
}

int RunCli(int argc, const char* const* argv) {
  CLI::App app;
  BuildApp(app);
  return ParseAndRun(app, argc, argv);
}

}  // namespace hapticlab::cli
