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

void Diagnostics::Add(std::string file, int line, std::string field, std::string message) {
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
