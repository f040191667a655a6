#pragma once
/// @file Long-format data (one row per observation) as analysts keep it: text key columns
/// and one numeric response, read from CSV or built in code.

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace hapticlab::stats {

/// A long-format table: `keys[c][r]` is key column c of row r; `y[r]` the response.
struct LongTable {
  std::string source;  ///< file name, for messages
  std::vector<std::string> key_names;
  std::vector<std::vector<std::string>> keys;
  std::vector<double> y;  ///< NaN: a missing response (allow_missing)
  std::string y_name;
  std::vector<std::size_t> lines;  ///< source line of each row (empty when built in code)

  std::size_t rows() const { return y.size(); }
  /// Index of a key column; throws InputError naming the source and the column.
  std::size_t Key(const std::string& name) const;
  /// Rows whose key columns equal the given values.
  LongTable Where(const std::vector<std::pair<std::string, std::string>>& equal) const;
  /// Mean response per combination of `by` columns (the other keys are dropped). Rows are
  /// ordered by the combination (sorted). Used to average repetitions per subject x cell.
  LongTable Average(const std::vector<std::string>& by) const;
  /// Sorted distinct values of a key column.
  std::vector<std::string> Levels(const std::string& name) const;
};

/// Which rows of a CSV to read: those whose columns equal every `equal` value and differ
/// from every `not_equal` value. Rows left out are never checked (an empty key cell or a
/// missing response there is no error).
struct RowFilter {
  std::vector<std::pair<std::string, std::string>> equal;
  std::vector<std::pair<std::string, std::string>> not_equal;
};

/// Reads a CSV: `dv` must be numeric in every kept row; `key_columns` are kept as text.
/// Empty or non-numeric responses are errors naming file, line and column (missing data is
/// never silently dropped). With `allow_missing`, an empty or `NA` response is read as NaN
/// (for the ANOVA, which drops and names the subject, as afex does); anything else
/// non-numeric is still an error.
/// Only rows that pass `keep` are read (filter columns must exist).
LongTable ReadLongCsv(const std::string& path, const std::string& dv,
                      const std::vector<std::string>& key_columns, bool allow_missing = false,
                      const RowFilter& keep = {});

/// Splits "a,b,c" into {"a","b","c"} (empty parts dropped).
std::vector<std::string> SplitList(const std::string& s);

}  // namespace hapticlab::stats
