#pragma once
// The hapticlab command line as one function, so that the binary and the tests build the
// same command tree.

#include <CLI/CLI.hpp>

namespace hapticlab::cli {

/// Registers every command group of `hapticlab` on `app` (its description, version flag
/// and the requirement of one subcommand included).
void BuildApp(CLI::App& app);

/// Builds the app, parses `argv` and runs the chosen command: the process's exit code
/// (0 ok, 1 the work failed, 2 bad usage or bad input, 3 a stopped session).
int RunCli(int argc, const char* const* argv);

}  // namespace hapticlab::cli
