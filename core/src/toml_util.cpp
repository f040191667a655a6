#include "hapticlab/core/toml_util.hpp"

#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"

namespace hapticlab {

toml::table ParseTomlText(std::string_view text, const std::string& name) {
  CheckTomlLimits(text, name);  // toml++ recurses per dotted part: refuse hostile input first
  try {
    return toml::parse(text, name);
  } catch (const toml::parse_error& e) {
    const auto& at = e.source().begin;
    throw InputError(name, static_cast<int>(at.line), "",
                     "column " + std::to_string(at.column) + ": " + std::string(e.description()));
  }
}

toml::table ParseTomlFile(const std::string& path, const std::string& what) {
  return ParseTomlText(ReadTextFile(path, what, kTomlMaxBytes), path);
}

}  // namespace hapticlab
