#pragma once
/// @file Small file helpers shared by the readers of user input and the writers of results.

#include <cstddef>
#include <string>
#include <string_view>

namespace hapticlab {

/// Whole file as text. @throws InputError naming the file ("cannot open <what>", or larger
/// than `max_bytes`).
std::string ReadTextFile(const std::string& path, const std::string& what = "file",
                         std::size_t max_bytes = std::size_t{256} << 20);

/// Writes `text` to `path`, replacing what was there (bytes as given: no newline
/// translation). The writer of every whole-file result (models, reports, CSV tables).
/// @throws std::runtime_error "<path>: cannot write" when the file cannot be created, or
/// "<path>: write failed" when writing or closing it fails (a full disk): the environment
/// failing, not bad input (docs/architecture.md, "Errors").
void WriteTextFile(const std::string& path, std::string_view text);

/// Limits every TOML reader enforces before toml++ parses a text (docs/studies.md, "Input
/// limits"). toml++ recurses per dotted key part and per nesting level, so a hostile file
/// (`a.a.a....` with 50,000 parts) would otherwise overflow the stack.
inline constexpr std::size_t kTomlMaxBytes = std::size_t{64} << 20;  ///< whole document
inline constexpr int kTomlMaxKeyParts = 32;            ///< dotted parts in one key or table header
inline constexpr std::size_t kTomlMaxKeyBytes = 1024;  ///< one key, all its parts and dots
inline constexpr int kTomlMaxNesting = 32;             ///< nested arrays and inline tables

/// Checks a TOML text against the limits above with a small lexer (strings, comments,
/// keys, brackets); it never recurses. @throws InputError naming `file`, the line and the key
/// when a limit is exceeded. Text that is not valid TOML is left for toml++ to report.
void CheckTomlLimits(std::string_view text, const std::string& file);

}  // namespace hapticlab
