// Linear mixed models: formula parsing and the fixed (X) and random (Z) design matrices, with
// R's conventions (terms ordered by degree, sum-to-zero contrasts, lme4's term order).

#include "lmm_design.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <set>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::stats {
namespace {

std::string Strip(const std::string& s) {
  std::string o;
  for (char c : s)
    if (!std::isspace(static_cast<unsigned char>(c))) o += c;
  return o;
}

// Splits at `sep` outside parentheses.
std::vector<std::string> SplitTop(const std::string& s, char sep) {
  std::vector<std::string> out;
  int depth = 0;
  std::string cur;
  for (char c : s) {
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if (c == sep && depth == 0) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

bool ValidName(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.')) return false;
  return true;
}

// "a*b:c" -> terms a, b:c, a:b:c ("*" expands to all interactions of its operands).
void AddTerms(const std::string& piece, std::vector<std::vector<std::string>>& terms,
              const std::string& source) {
  const auto factors = SplitTop(piece, '*');
  std::vector<std::vector<std::string>> ops;
  for (const auto& f : factors) {
    auto vars = SplitTop(f, ':');
    for (const auto& v : vars)
      if (!ValidName(v))
        throw InputError(source, 0, "formula",
                         "expected a column name, got '" + v + "' in '" + piece + "'");
    ops.push_back(vars);
  }
  const std::size_t m = ops.size();
  for (std::size_t mask = 1; mask < (std::size_t{1} << m); ++mask) {
    std::vector<std::string> t;
    for (std::size_t i = 0; i < m; ++i)
      if (mask & (std::size_t{1} << i)) t.insert(t.end(), ops[i].begin(), ops[i].end());
    terms.push_back(t);
  }
}

// Drops repeated terms (a:b equals b:a) and orders by degree, stably (as R's terms()).
void Canonical(std::vector<std::vector<std::string>>& terms) {
  std::vector<std::vector<std::string>> out;
  std::set<std::set<std::string>> seen;
  for (const auto& t : terms) {
    std::set<std::string> k(t.begin(), t.end());
    if (seen.insert(k).second) out.push_back(t);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return a.size() < b.size(); });
  terms = out;
}

// One column of the data: a factor (sorted levels, level index per row) or numeric.
struct Column {
  bool numeric = false;
  std::vector<double> value;
  std::vector<std::string> levels;
  std::vector<int> level;
};

Column ReadColumn(const LongTable& data, const std::string& name, bool force_factor) {
  const auto c = data.Key(name);
  Column col;
  const auto& raw = data.keys[c];
  col.numeric = !force_factor;
  for (const auto& s : raw) {
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v)) {
      col.numeric = false;
      break;
    }
    col.value.push_back(v);
  }
  if (col.numeric) return col;
  col.value.clear();
  col.levels = data.Levels(name);
  if (col.levels.size() < 2)
    throw InputError(
        data.source, 0, name,
        "a factor needs at least 2 levels, found " + std::to_string(col.levels.size()));
  for (const auto& s : raw)
    col.level.push_back(static_cast<int>(std::lower_bound(col.levels.begin(), col.levels.end(), s) -
                                         col.levels.begin()));
  return col;
}

// Columns of a term (product of its variables' codings, first variable fastest) in `out`.
// `full`: a lone factor without an intercept gets one indicator per level (as R).
void TermColumns(const std::vector<std::string>& term, std::map<std::string, Column>& cols,
                 std::size_t n, bool full, std::vector<Eigen::VectorXd>& out,
                 std::vector<std::string>& names) {
  std::vector<Eigen::VectorXd> cur{Eigen::VectorXd::Ones(static_cast<Eigen::Index>(n))};
  std::vector<std::string> cur_names{""};
  for (const auto& v : term) {
    const Column& c = cols.at(v);
    std::vector<Eigen::VectorXd> code;
    std::vector<std::string> code_names;
    if (c.numeric) {
      code.emplace_back(
          Eigen::Map<const Eigen::VectorXd>(c.value.data(), static_cast<Eigen::Index>(n)));
      code_names.push_back(v);
    } else {
      const int k = static_cast<int>(c.levels.size());
      const int ncol = full ? k : k - 1;
      for (int j = 0; j < ncol; ++j) {
        Eigen::VectorXd x(static_cast<Eigen::Index>(n));
        for (std::size_t r = 0; r < n; ++r)
          x[static_cast<Eigen::Index>(r)] =
              c.level[r] == j ? 1.0 : (!full && c.level[r] == k - 1 ? -1.0 : 0.0);
        code.push_back(x);
        code_names.push_back(full ? v + c.levels[static_cast<std::size_t>(j)]
                                  : v + std::to_string(j + 1));
      }
    }
    std::vector<Eigen::VectorXd> next;
    std::vector<std::string> next_names;
    for (std::size_t b = 0; b < code.size(); ++b)
      for (std::size_t a = 0; a < cur.size(); ++a) {  // earlier variables vary fastest
        next.emplace_back(cur[a].cwiseProduct(code[b]));
        next_names.push_back(cur_names[a].empty() ? code_names[b]
                                                  : cur_names[a] + ":" + code_names[b]);
      }
    cur = next;
    cur_names = next_names;
  }
  out.insert(out.end(), cur.begin(), cur.end());
  names.insert(names.end(), cur_names.begin(), cur_names.end());
}

std::string Join(const std::vector<std::string>& t) {
  std::string s;
  for (const auto& v : t) s += (s.empty() ? "" : ":") + v;
  return s;
}

}  // namespace

std::vector<std::string> LmmFormula::Columns() const {
  std::vector<std::string> c{response};
  auto add = [&](const std::string& v) {
    if (std::find(c.begin(), c.end(), v) == c.end()) c.push_back(v);
  };
  for (const auto& t : fixed)
    for (const auto& v : t) add(v);
  for (const auto& r : random) {
    for (const auto& t : r.terms)
      for (const auto& v : t) add(v);
    add(r.group);
  }
  return c;
}

LmmFormula ParseLmmFormula(const std::string& formula, const std::string& source) {
  const std::string s = Strip(formula);
  const auto tilde = s.find('~');
  if (tilde == std::string::npos || s.find('~', tilde + 1) != std::string::npos)
    throw InputError(source, 0, "formula", "expected 'response ~ terms', got '" + formula + "'");
  LmmFormula f;
  f.response = s.substr(0, tilde);
  if (!ValidName(f.response))
    throw InputError(source, 0, "formula", "expected a response column before '~'");
  if (s.find('-') != std::string::npos)
    throw InputError(source, 0, "formula",
                     "'-' is not supported (the fixed part always has an intercept)");
  for (const auto& piece : SplitTop(s.substr(tilde + 1), '+')) {
    if (piece.empty()) throw InputError(source, 0, "formula", "empty term in '" + formula + "'");
    if (piece.front() == '(') {
      if (piece.back() != ')')
        throw InputError(source, 0, "formula", "unbalanced parentheses in '" + piece + "'");
      const std::string in = piece.substr(1, piece.size() - 2);
      const auto bar = in.find('|');
      if (bar == std::string::npos || in.find('|', bar + 1) != std::string::npos)
        throw InputError(source, 0, "formula",
                         "expected '(terms | group)', got '" + piece + "' ('||' is not supported)");
      LmmFormula::Random r;
      r.group = in.substr(bar + 1);
      if (!ValidName(r.group))
        throw InputError(source, 0, "formula",
                         "expected a grouping column after '|' in '" + piece + "'");
      bool saw_zero = false;
      for (const auto& t : SplitTop(in.substr(0, bar), '+')) {
        if (t == "1") continue;
        if (t == "0") {
          saw_zero = true;
          continue;
        }
        AddTerms(t, r.terms, source);
      }
      r.intercept = !saw_zero;
      Canonical(r.terms);
      if (!r.intercept && r.terms.empty())
        throw InputError(source, 0, "formula", "random term '" + piece + "' is empty");
      f.random.push_back(r);
    } else if (piece == "1") {
      continue;
    } else if (piece == "0") {
      throw InputError(source, 0, "formula",
                       "a fixed part without intercept ('0') is not supported");
    } else {
      AddTerms(piece, f.fixed, source);
    }
  }
  if (f.random.empty())
    throw InputError(
        source, 0, "formula",
        "no random term such as '(1 | participant)': use rm-anova for a fixed-effects model");
  Canonical(f.fixed);
  return f;
}

namespace detail {

LmmDesign BuildLmmDesign(const LongTable& data, const LmmFormula& f) {
  const std::size_t n = data.rows();
  std::map<std::string, Column> cols;
  std::set<std::string> groups;
  for (const auto& r : f.random) groups.insert(r.group);
  for (const auto& name : f.Columns())
    if (name != f.response && !cols.count(name))
      cols.emplace(name, ReadColumn(data, name, groups.count(name) > 0));
  for (const auto& g : groups)
    if (cols.at(g).numeric) throw InputError(data.source, 0, g, "grouping column must be a factor");
  LmmDesign d;
  d.y = Eigen::Map<const Eigen::VectorXd>(data.y.data(), static_cast<Eigen::Index>(n));
  std::vector<Eigen::VectorXd> xc{Eigen::VectorXd::Ones(static_cast<Eigen::Index>(n))};
  d.x_names = {"(Intercept)"};
  for (const auto& t : f.fixed) {
    for (const auto& v : t)
      if (groups.count(v) && cols.at(v).numeric)
        throw InputError(data.source, 0, v, "grouping column used as a number");
    LmmDesign::Term term{Join(t), {}};
    const auto before = xc.size();
    TermColumns(t, cols, n, false, xc, d.x_names);
    for (auto j = before; j < xc.size(); ++j) term.columns.push_back(static_cast<int>(j));
    d.x_terms.push_back(term);
  }
  d.X.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(xc.size()));
  for (std::size_t j = 0; j < xc.size(); ++j) d.X.col(static_cast<Eigen::Index>(j)) = xc[j];

  // Random terms in lme4's order: decreasing number of grouping levels (stable).
  std::vector<std::size_t> order(f.random.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return cols.at(f.random[a].group).levels.size() > cols.at(f.random[b].group).levels.size();
  });
  std::vector<Eigen::Triplet<double>> trip;
  int offset = 0;
  for (auto i : order) {
    const auto& r = f.random[i];
    std::vector<Eigen::VectorXd> zc;
    LmmDesign::Block b;
    b.group = r.group;
    if (r.intercept) {
      zc.emplace_back(Eigen::VectorXd::Ones(static_cast<Eigen::Index>(n)));
      b.names.emplace_back("(Intercept)");
    }
    const bool full = !r.intercept && r.terms.size() == 1 && r.terms[0].size() == 1 &&
                      !cols.at(r.terms[0][0]).numeric;
    for (const auto& t : r.terms) {
      bool has_factor = false;
      for (const auto& v : t) has_factor = has_factor || !cols.at(v).numeric;
      if (!r.intercept && has_factor && !full)
        throw InputError(
            data.source, 0, "formula",
            "a random term without intercept may hold numeric columns or one factor only");
      TermColumns(t, cols, n, full, zc, b.names);
    }
    const Column& g = cols.at(r.group);
    b.levels = static_cast<int>(g.levels.size());
    b.p = static_cast<int>(zc.size());
    b.offset = offset;
    for (std::size_t row = 0; row < n; ++row)
      for (int c = 0; c < b.p; ++c) {
        const double v = zc[static_cast<std::size_t>(c)][static_cast<Eigen::Index>(row)];
        if (v != 0.0) trip.emplace_back(static_cast<int>(row), offset + g.level[row] * b.p + c, v);
      }
    offset += b.levels * b.p;
    d.blocks.push_back(b);
  }
  d.Z.resize(static_cast<Eigen::Index>(n), offset);
  d.Z.setFromTriplets(trip.begin(), trip.end());
  return d;
}

}  // namespace detail
}  // namespace hapticlab::stats
