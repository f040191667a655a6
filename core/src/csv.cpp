#include "hapticlab/core/csv.hpp"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "csv_internal.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"

namespace hapticlab {
namespace internal {

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

// Splits one CSV line into cells, honouring double quotes.
std::vector<std::string> SplitLine(const std::string& line, const std::string& file, int lineno) {
  std::vector<std::string> cells;
  std::string cell;
  bool quoted = false;
  bool was_quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"') {
        if (i + 1 < line.size() && line[i + 1] == '"') {
          cell += '"';
          ++i;
        } else {
          quoted = false;
        }
      } else {
        cell += c;
      }
    } else if (c == '"') {
      quoted = true;
      was_quoted = true;
    } else if (c == ',') {
      cells.push_back(was_quoted ? cell : Trim(cell));
      cell.clear();
      was_quoted = false;
    } else {
      cell += c;
    }
  }
  if (quoted) throw InputError(file, lineno, "", "unterminated quoted cell");
  cells.push_back(was_quoted ? cell : Trim(cell));
  return cells;
}

}  // namespace internal

using internal::SplitLine;
using internal::Trim;

std::optional<std::size_t> CsvTable::Find(const std::string& column) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == column) return i;
  return std::nullopt;
}

std::size_t CsvTable::Require(const std::string& column) const {
  if (auto i = Find(column)) return *i;
  std::string have;
  for (const auto& h : header) have += (have.empty() ? "" : ", ") + h;
  throw InputError(file, 0, column, "column is missing (columns present: " + have + ")");
}

double CsvTable::Number(std::size_t row, std::size_t column) const {
  const std::string& s = rows.at(row).at(column);
  const int line = row < row_lines.size() ? row_lines[row] : 0;
  const std::string& name = column < header.size() ? header[column] : std::string();
  if (s.empty()) throw InputError(file, line, name, "empty cell, expected a number");
  const char* begin = s.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(begin, &end);
  if (end == begin || *end != '\0')
    throw InputError(file, line, name, "expected a number, got '" + s + "'");
  return v;
}

CsvTable ParseCsv(const std::string& text, const std::string& name) {
  CsvTable t;
  t.file = name;
  // A UTF-8 byte-order mark (spreadsheet exports) is not part of the first column's name.
  std::istringstream in(text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? text.substr(3) : text);
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (Trim(line).empty()) continue;
    if (t.header.empty() && line[0] == '#') {
      std::string c = line.substr(1);
      t.comments.push_back(Trim(c));
      const auto colon = c.find(':');
      if (colon != std::string::npos)
        t.metadata[Trim(c.substr(0, colon))] = Trim(c.substr(colon + 1));
      continue;
    }
    auto cells = SplitLine(line, name, lineno);
    if (t.header.empty()) {
      t.header = std::move(cells);
      continue;
    }
    if (cells.size() != t.header.size())
      throw InputError(name, lineno, "",
                       "row has " + std::to_string(cells.size()) + " cells, header has " +
                           std::to_string(t.header.size()));
    // Cells are held as strings (about 40 bytes each): the table is bounded before it grows
    // past a few hundred MB (measurement CSVs are streamed instead: measurement.cpp).
    if ((t.rows.size() + 1) * t.header.size() > internal::kCsvMaxCells)
      throw InputError(name, lineno, "",
                       "more than " + std::to_string(internal::kCsvMaxCells) +
                           " cells; a table this large is not read as text cells");
    t.rows.push_back(std::move(cells));
    t.row_lines.push_back(lineno);
  }
  if (t.header.empty()) throw InputError(name, 0, "", "no header row found");
  return t;
}

CsvTable ReadCsv(const std::string& path) { return ParseCsv(ReadTextFile(path, "CSV file"), path); }

std::string CsvEscape(const std::string& cell) {
  if (cell.find_first_of(",\"\n\r") == std::string::npos) return cell;
  std::string s = "\"";
  for (char c : cell) {
    if (c == '"') s += '"';
    s += c;
  }
  return s + "\"";
}

}  // namespace hapticlab
