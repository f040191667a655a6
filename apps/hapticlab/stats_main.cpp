// hapticlab-stats: the `hapticlab stats` commands in a lean binary. It links only the
// statistics (core, stats, Boost.Math, Eigen, CLI11, fmt, JSON) with --as-needed, so a call
// does not load OpenCV, Ceres, PortAudio, GLFW, SQLite or PLplot at start-up (the full
// `hapticlab` binary does, which made each `hapticlab stats` call pay ~0.14 s; issue #24).

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/version.hpp"

int main(int argc, char** argv) {
  using namespace hapticlab::cli;
  // ParseAndRun reports every error of a command; this catches what building the command tree
  // itself could throw (e.g. std::bad_alloc), which would otherwise end in std::terminate.
  try {
    CLI::App app{
        "hapticlab-stats: the statistics of 'hapticlab stats' (rm-anova, tukey, kruskal,\n"
        "shapiro, lmm, psychometric) on any CSV, in a binary that starts fast (see "
        "docs/analysis.md).\n"
        "Exit codes: 0 ok, 1 the work failed, 2 bad usage or bad input.",
        "hapticlab-stats"};
    app.set_version_flag("--version", std::string("hapticlab-stats ") + hapticlab::kVersion + " (" +
                                          hapticlab::kGitSha + ")");
    app.require_subcommand(1);
    AddStatsCommands(app);
    return ParseAndRun(app, argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hapticlab-stats: internal error: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "hapticlab-stats: internal error\n");
  }
  return 1;
}
