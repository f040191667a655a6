#include "hapticlab/core/diagnostics.hpp"

#include <utility>

namespace hapticlab {

std::string Diagnostic::ToString() const {
  std::string s = file;
  if (line > 0) s += ":" + std::to_string(line);
  if (!s.empty()) s += ": ";
  if (!field.empty()) s += field + ": ";
  s += message;
  return s;
}

// A hostile file must not grow the list (and the message) without bound: the first
// kMaxDiagnostics problems are kept, then one line says that more were found.
constexpr std::size_t kMaxDiagnostics = 100;

void Diagnostics::Add(std::string file, int line, std::string field, std::string message) {
  if (items_.size() > kMaxDiagnostics) return;
  if (items_.size() == kMaxDiagnostics) {
    items_.push_back({std::move(file), 0, "",
                      "... and more problems (only the first " + std::to_string(kMaxDiagnostics) +
                          " are listed)"});
    return;
  }
  items_.push_back({std::move(file), line, std::move(field), std::move(message)});
}

std::string Diagnostics::ToString() const {
  std::string s;
  for (const auto& d : items_) {
    if (!s.empty()) s += "\n";
    s += d.ToString();
  }
  return s;
}

void Diagnostics::ThrowIfAny() const {
  if (!items_.empty()) throw InputError(*this);
}

InputError::InputError(const Diagnostics& d)
    : std::runtime_error(d.ToString()), diagnostics_(d.items()) {}

InputError::InputError(std::string file, int line, std::string field, std::string message)
    : std::runtime_error(Diagnostic{file, line, field, message}.ToString()),
      diagnostics_{{std::move(file), line, std::move(field), std::move(message)}} {}

}  // namespace hapticlab
