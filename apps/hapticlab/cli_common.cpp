#include "cli_common.hpp"

#include <fmt/core.h>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"

namespace hapticlab::cli {

int Guard(const std::function<int()>& body) {
  try {
    return body();
  } catch (const InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return kExitBadInput;
  } catch (const std::filesystem::filesystem_error& e) {
    // The environment refused a file operation: the path and the reason, as a sentence.
    fmt::print(stderr, "failed: {}: {}\n", e.path1().string(), e.code().message());
    return kExitFailure;
  } catch (const PreconditionError& e) {
    fmt::print(stderr, "internal error (please report): {}\n", e.what());
    return kExitFailure;
  } catch (const std::exception& e) {
    fmt::print(stderr, "failed: {}\n", e.what());
    return kExitFailure;
  }
}

void RunGuarded(const std::function<int()>& body) {
  const int rc = Guard(body);
  if (rc != kExitOk) throw CLI::RuntimeError(rc);
}

void RunGuarded(const std::map<std::string, std::string>& flags, const std::function<int()>& body) {
  RunGuarded([&] {
    int rc = kExitOk;
    WithFlags(flags, [&] { rc = body(); });
    return rc;
  });
}

int ParseAndRun(CLI::App& app, int argc, const char* const* argv) {
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

void WithFlags(const std::map<std::string, std::string>& flags, const std::function<void()>& body) {
  try {
    body();
  } catch (const InputError& e) {
    Diagnostics d;
    for (const auto& x : e.diagnostics()) {
      const auto flag = flags.find(x.field);
      d.Add(x.file, x.line, flag == flags.end() ? x.field : flag->second, x.message);
    }
    d.ThrowIfAny();
    throw;  // an InputError without diagnostics: as it was
  }
}

void PrintJson(const nlohmann::json& j) { fmt::print("{}\n", JsonText(j, 2)); }

std::string JsonText(const nlohmann::json& j, int indent) {
  // Strings from user files and paths may hold bytes that are not UTF-8: replaced (U+FFFD),
  // never thrown as nlohmann's "invalid UTF-8" text.
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::function<void(const std::string&)> StderrLog(bool quiet) {
  if (quiet) return [](const std::string&) {};
  return [](const std::string& s) { fmt::print(stderr, "{}\n", s); };
}

void AddPlanned(CLI::App& parent, const std::string& name, const std::string& description,
                const std::string& issue) {
  auto* cmd = parent.add_subcommand(name, description + " [not in this build yet: " + issue + "]");
  cmd->allow_extras();
  cmd->callback([name, issue] {
    fmt::print(stderr, "hapticlab {}: not available in this build yet ({}).\n", name, issue);
    throw CLI::RuntimeError(kExitFailure);
  });
}

}  // namespace hapticlab::cli
