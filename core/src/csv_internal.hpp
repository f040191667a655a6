#pragma once
// Pieces of the CSV reader shared with the streaming measurement reader (measurement.cpp).

#include <cstddef>
#include <string>
#include <vector>

namespace hapticlab::internal {

/// Cells a CsvTable may hold (docs/formats.md, "Bounds"): 10 million, about 400 MB as strings.
inline constexpr std::size_t kCsvMaxCells = 10'000'000;

/// `s` without leading and trailing spaces, tabs and carriage returns.
std::string Trim(const std::string& s);

/// One CSV line's cells, honouring double quotes. @throws InputError (file, line) on an
/// unterminated quoted cell.
std::vector<std::string> SplitLine(const std::string& line, const std::string& file, int lineno);

}  // namespace hapticlab::internal
