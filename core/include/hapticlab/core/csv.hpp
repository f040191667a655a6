#pragma once
/// @file A small CSV reader for tidy tables (measurements, long-format ratings, exports).

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace hapticlab {

/// A CSV table held as text cells, with the source line of every row for diagnostics.
/// Lines starting with '#' before the header are metadata comments (`# key: value`).
/// Quoted cells ("a,b" and "" escapes) are supported. No cell may span lines.
struct CsvTable {
  std::string file;                             ///< source path, for messages
  std::vector<std::string> comments;            ///< comment lines without the leading '#'
  std::map<std::string, std::string> metadata;  ///< `# key: value` comments
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<int> row_lines;  ///< 1-based source line of each row

  /// Index of a column, or nullopt.
  std::optional<std::size_t> Find(const std::string& column) const;
  /// Index of a column; throws InputError naming the file and column when absent.
  std::size_t Require(const std::string& column) const;
  /// Cell parsed as a finite or non-finite double; throws InputError with file, line and
  /// column when the text is not a number.
  double Number(std::size_t row, std::size_t column) const;
};

/// Reads a CSV file. Throws InputError (file, line) on I/O or shape errors.
CsvTable ReadCsv(const std::string& path);
/// Parses CSV text; `name` is used in messages.
CsvTable ParseCsv(const std::string& text, const std::string& name);
/// Quotes a cell when it holds a comma, quote or newline.
std::string CsvEscape(const std::string& cell);

}  // namespace hapticlab
