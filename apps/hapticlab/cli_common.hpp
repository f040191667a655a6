#pragma once
// Shared pieces of the hapticlab command line: exit codes and error reporting.

#include <CLI/CLI.hpp>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "hapticlab/core/enum_names.hpp"

namespace hapticlab::cli {

/// Exit codes of every command.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;   ///< the work failed (I/O, a fit that diverged, ...)
inline constexpr int kExitBadInput = 2;  ///< bad usage or bad input (message names file/line/field)
/// study run / resume: the session stopped before its end (the experimenter's Abort,
/// --stop-after, or too many untouched trials); what was completed is recorded and
/// 'hapticlab study resume' continues it.
inline constexpr int kExitStopped = 3;

/// The file an InputError about a command-line argument names (docs/architecture.md, "Errors").
inline constexpr const char* kCommandLine = "<command line>";

/// Runs a command body, mapping exceptions to exit codes and messages on stderr:
/// InputError -> 2, anything else -> 1.
int Guard(const std::function<int()>& body);

/// Guard for CLI11 callbacks: runs `body` and turns a non-zero exit into CLI11's exit path.
void RunGuarded(const std::function<int()>& body);

/// RunGuarded with WithFlags: the library's names for what the user gave ("db",
/// "participant", ...) are shown as the options that gave them (`flags`: field -> "--flag").
void RunGuarded(const std::map<std::string, std::string>& flags, const std::function<int()>& body);

/// Parses `argv` with `app` (running the chosen command's callback) and returns the process's
/// exit code: a command's own (CLI::RuntimeError), 0 for --help and --version, 2 for bad usage.
int ParseAndRun(CLI::App& app, int argc, const char* const* argv);

/// Runs `body`; an InputError it throws is thrown again with each field found in `flags`
/// (a library's name for it, e.g. "firmware") replaced by the command-line option that set
/// it ("--firmware"): library code names its own fields, never the CLI's flags.
void WithFlags(const std::map<std::string, std::string>& flags, const std::function<void()>& body);

/// A command's --json output: `j` indented by two spaces, then a newline, on stdout.
void PrintJson(const nlohmann::json& j);

/// `j` as text (`indent` < 0: one line); bytes that are not UTF-8 become U+FFFD.
std::string JsonText(const nlohmann::json& j, int indent = -1);

/// The progress log of a long command: each line to stderr, or nowhere when `quiet`.
std::function<void(const std::string&)> StderrLog(bool quiet);

/// Adds an option whose value is one of `table`'s names (an EnumTable, core/enum_names.hpp):
/// CLI11 checks it against the names, which --help lists in table order with `value`'s
/// current name as the default, and the name is parsed into `value` once, when given.
/// `value` must outlive the parse.
template <typename E, std::size_t N>
CLI::Option* AddEnumOption(CLI::App* cmd, const std::string& name, E& value,
                           const EnumTable<E, N>& table, const std::string& description) {
  return cmd
      ->add_option_function<std::string>(
          name, [&value, &table](const std::string& s) { value = *FromName(table, s); },
          description)
      ->check(CLI::IsMember(Names(table)))
      ->default_str(std::string(NameOf(table, value)));
}

/// AddEnumOption for a value with no default: nullopt until the option is given.
template <typename E, std::size_t N>
CLI::Option* AddEnumOption(CLI::App* cmd, const std::string& name, std::optional<E>& value,
                           const EnumTable<E, N>& table, const std::string& description) {
  return cmd
      ->add_option_function<std::string>(
          name, [&value, &table](const std::string& s) { value = FromName(table, s); }, description)
      ->check(CLI::IsMember(Names(table)));
}

/// Registers a command group whose work lands with a later issue; running it explains that.
void AddPlanned(CLI::App& parent, const std::string& name, const std::string& description,
                const std::string& issue);

}  // namespace hapticlab::cli
