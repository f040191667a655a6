#pragma once
/// @file Diagnostics for untrusted input: every problem with its file, line and field.

#include <stdexcept>
#include <string>
#include <vector>

namespace hapticlab {

/// One problem found in an input file.
struct Diagnostic {
  std::string file;     ///< path of the input as given by the user
  int line = 0;         ///< 1-based line number; 0 when not known
  std::string field;    ///< key, column or field name; empty when not applicable
  std::string message;  ///< what is wrong and what was expected

  /// "file:line: field: message", omitting the parts that are empty.
  std::string ToString() const;
};

/// Collects every problem in an input so that the user sees all of them at once.
class Diagnostics {
 public:
  void Add(std::string file, int line, std::string field, std::string message);
  bool empty() const { return items_.empty(); }
  std::size_t size() const { return items_.size(); }
  const std::vector<Diagnostic>& items() const { return items_; }
  /// All problems, one per line.
  std::string ToString() const;
  /// Throws InputError listing every problem when any was added.
  void ThrowIfAny() const;

 private:
  std::vector<Diagnostic> items_;
};

/// Bad user input (files, arguments). The CLI maps it to exit code 2.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const Diagnostics& d);
  InputError(std::string file, int line, std::string field, std::string message);
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }

 private:
  std::vector<Diagnostic> diagnostics_;
};

}  // namespace hapticlab
