// hapticlab: the one command line of HapticLab.

#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <csignal>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/version.hpp"

int main(int argc, char** argv) {
  using namespace hapticlab::cli;
  // A file-size limit (ulimit -f) must end in a clear error from the failed write (EFBIG),
  // like a full disk, not in SIGXFSZ killing the process mid-session.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{
      "HapticLab: model real textures, render them on a force-feedback device plus a\n"
      "vibrotactile actuator, run psychophysical studies comparing real and virtual\n"
      "textures, and analyse the ratings. Run 'hapticlab COMMAND --help' for details.\n"
      "Exit codes: 0 ok, 1 the work failed, 2 bad usage or bad input.",
      "hapticlab"};
  app.set_version_flag("--version", fmt::format("hapticlab {} ({})", hapticlab::kVersion,
                                                 hapticlab::kGitSha));
  app.require_subcommand(1);

  RegisterExport(app);
  RegisterModel(app);
  RegisterDemo(app);
  RegisterStats(app);
  RegisterStudy(app);
  RegisterAnalyze(app);
  RegisterWorkbench(app);
  RegisterDevice(app);
  RegisterParticipant(app);
  RegisterRig(app);
  RegisterDb(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? kExitOk : kExitBadInput;
  }
  return kExitOk;
}
