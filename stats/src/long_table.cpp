#include "hapticlab/stats/long_table.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::stats {

std::size_t LongTable::Key(const std::string& name) const {
  for (std::size_t i = 0; i < key_names.size(); ++i)
    if (key_names[i] == name) return i;
  throw InputError(source, 0, name, "no such column");
}

LongTable LongTable::Where(const std::vector<std::pair<std::string, std::string>>& equal) const {
  std::vector<std::pair<std::size_t, std::string>> cond;
  for (const auto& [k, v] : equal) cond.emplace_back(Key(k), v);
  LongTable out;
  out.source = source;
  out.key_names = key_names;
  out.y_name = y_name;
  out.keys.assign(key_names.size(), {});
  for (std::size_t r = 0; r < rows(); ++r) {
    bool ok = true;
    for (const auto& [c, v] : cond) ok = ok && keys[c][r] == v;
    if (!ok) continue;
    for (std::size_t c = 0; c < key_names.size(); ++c) out.keys[c].push_back(keys[c][r]);
    out.y.push_back(y[r]);
    if (r < lines.size()) out.lines.push_back(lines[r]);
  }
  return out;
}

LongTable LongTable::Average(const std::vector<std::string>& by) const {
  std::vector<std::size_t> cols;
  for (const auto& b : by) cols.push_back(Key(b));
  std::map<std::vector<std::string>, std::vector<double>> acc;
  for (std::size_t r = 0; r < rows(); ++r) {
    std::vector<std::string> k;
    for (auto c : cols) k.push_back(keys[c][r]);
    acc[k].push_back(y[r]);
  }
  LongTable out;
  out.source = source;
  out.key_names = by;
  out.y_name = y_name;
  out.keys.assign(by.size(), {});
  for (const auto& [k, v] : acc) {
    for (std::size_t c = 0; c < by.size(); ++c) out.keys[c].push_back(k[c]);
    // Two-pass mean, as R's mean(): the sum's rounding error is corrected by the mean of
    // the residuals, so cell means agree with R's to the last bit far more often.
    double m = 0;
    for (double x : v) m += x;
    m /= static_cast<double>(v.size());
    double r = 0;
    for (double x : v) r += x - m;
    out.y.push_back(m + r / static_cast<double>(v.size()));
  }
  return out;
}

std::vector<std::string> LongTable::Levels(const std::string& name) const {
  const auto c = Key(name);
  std::vector<std::string> v(keys[c]);
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

LongTable ReadLongCsv(const std::string& path, const std::string& dv,
                      const std::vector<std::string>& key_columns, bool allow_missing,
                      const RowFilter& keep) {
  const CsvTable t = ReadCsv(path);
  std::vector<std::pair<std::size_t, std::string>> eq, ne;
  for (const auto& [k, v] : keep.equal) eq.emplace_back(t.Require(k), v);
  for (const auto& [k, v] : keep.not_equal) ne.emplace_back(t.Require(k), v);
  LongTable out;
  out.source = path;
  out.y_name = dv;
  out.key_names = key_columns;
  const std::size_t cy = t.Require(dv);
  std::vector<std::size_t> ck;
  for (const auto& k : key_columns) ck.push_back(t.Require(k));
  out.keys.assign(key_columns.size(), {});
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    // Filter first: cells of rows left out are never checked.
    bool kept = true;
    for (const auto& [c, v] : eq) kept = kept && t.rows[r][c] == v;
    for (const auto& [c, v] : ne) kept = kept && t.rows[r][c] != v;
    if (!kept) continue;
    const std::string& raw = t.rows[r][cy];
    if (allow_missing && (raw.empty() || raw == "NA")) {
      out.y.push_back(std::numeric_limits<double>::quiet_NaN());
    } else {
      const double v = t.Number(r, cy);
      if (!std::isfinite(v)) throw InputError(path, t.row_lines[r], dv, "value is not finite");
      out.y.push_back(v);
    }
    out.lines.push_back(static_cast<std::size_t>(t.row_lines[r]));
    for (std::size_t c = 0; c < ck.size(); ++c) {
      const std::string& s = t.rows[r][ck[c]];
      if (s.empty()) throw InputError(path, t.row_lines[r], key_columns[c], "empty key cell");
      out.keys[c].push_back(s);
    }
  }
  return out;
}

std::vector<std::string> SplitList(const std::string& s) {
  std::vector<std::string> out;
  std::size_t a = 0;
  while (a <= s.size()) {
    const auto b = s.find(',', a);
    const auto part = s.substr(a, b == std::string::npos ? std::string::npos : b - a);
    if (!part.empty()) out.push_back(part);
    if (b == std::string::npos) break;
    a = b + 1;
  }
  return out;
}

}  // namespace hapticlab::stats
