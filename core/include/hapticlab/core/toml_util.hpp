#pragma once
/// @file The one way the readers of user TOML files parse them: size and nesting limits
/// first (core/io.hpp, CheckTomlLimits), then toml++, with a syntax error turned into an
/// InputError that names the file, the line and the column. Debian's toml++ is a compiled
/// library: a target including this header links tomlplusplus::tomlplusplus (core links it
/// privately, so that its compile definitions do not reach every target).

#include <toml++/toml.h>

#include <string>
#include <string_view>

namespace hapticlab {

/// Reads and parses the TOML file at `path` (`what` names it in "cannot open <what>").
/// @throws InputError naming `path` when the file cannot be read, exceeds the TOML limits
/// or is not valid TOML (with the line, and the column in the message).
toml::table ParseTomlFile(const std::string& path, const std::string& what = "file");

/// Parses a TOML text already in memory; `name` is the file it came from (or a label such as
/// "<command line>"), used in the diagnostics. @throws InputError as ParseTomlFile.
toml::table ParseTomlText(std::string_view text, const std::string& name);

}  // namespace hapticlab
