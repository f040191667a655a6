#pragma once
// Shared pieces of the hapticlab command line: exit codes and error reporting.

#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace hapticlab::cli {

/// Exit codes of every command.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;   ///< the work failed (I/O, a fit that diverged, ...)
inline constexpr int kExitBadInput = 2;  ///< bad usage or bad input (message names file/line/field)
/// study run / resume: the session stopped before its end (the experimenter's Abort,
/// --stop-after, or too many untouched trials); what was completed is recorded and
/// 'hapticlab study resume' continues it.
inline constexpr int kExitStopped = 3;

/// Runs a command body, mapping exceptions to exit codes and messages on stderr:
/// InputError and std::invalid_argument -> 2, anything else -> 1.
int Guard(const std::function<int()>& body);

/// Guard for CLI11 callbacks: runs `body` and turns a non-zero exit into CLI11's exit path.
void RunGuarded(const std::function<int()>& body);

/// Registers a command group whose work lands with a later issue; running it explains that.
void AddPlanned(CLI::App& parent, const std::string& name, const std::string& description,
                const std::string& issue);

}  // namespace hapticlab::cli
