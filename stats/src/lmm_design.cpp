// Linear mixed models: the fixed (X) and random (Z) design matrices (the formula is parsed in
// lmm_formula.cpp), with R's conventions (R's factor coding with contr.sum, lme4's term order).

#include "lmm_design.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <set>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::stats {
namespace {

// One column of the data: a factor (sorted levels, level index per row) or numeric.
struct Column {
  bool numeric = false;
  std::vector<double> value;
  std::vector<Eigen::VectorXd> basis;  ///< several numeric columns (poly): named v1, v2, ...
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
// `full(v)`: factor v gets one indicator per level instead of sum-to-zero contrasts (as R).
void TermColumns(const std::vector<std::string>& term, std::map<std::string, Column>& cols,
                 std::size_t n, const std::function<bool(const std::string&)>& full_of,
                 std::vector<Eigen::VectorXd>& out, std::vector<std::string>& names) {
  std::vector<Eigen::VectorXd> cur{Eigen::VectorXd::Ones(static_cast<Eigen::Index>(n))};
  std::vector<std::string> cur_names{""};
  for (const auto& v : term) {
    const Column& c = cols.at(v);
    const bool full = !c.numeric && full_of(v);
    std::vector<Eigen::VectorXd> code;
    std::vector<std::string> code_names;
    if (c.numeric && !c.basis.empty()) {
      for (std::size_t j = 0; j < c.basis.size(); ++j) {
        code.push_back(c.basis[j]);
        code_names.push_back(v + std::to_string(j + 1));
      }
    } else if (c.numeric) {
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

// The grouping factor of a random term: its column, or the interaction of its columns (levels
// are the combined keys "b:a", sorted; only combinations that occur, as lme4's factor()).
Column GroupColumn(const LongTable& data, const LmmFormula::Random& r,
                   const std::map<std::string, Column>& raw) {
  if (r.group_factors.size() == 1) return raw.at(r.group_factors[0]);
  std::vector<std::string> key(data.rows());
  for (const auto& g : r.group_factors) {
    const auto& k = data.keys[data.Key(g)];
    for (std::size_t i = 0; i < key.size(); ++i) key[i] += (key[i].empty() ? "" : ":") + k[i];
  }
  Column c;
  c.levels = key;
  std::sort(c.levels.begin(), c.levels.end());
  c.levels.erase(std::unique(c.levels.begin(), c.levels.end()), c.levels.end());
  if (c.levels.size() < 2)
    throw InputError(data.source, 0, r.group, "a grouping factor needs at least 2 levels");
  for (const auto& s : key)
    c.level.push_back(
        static_cast<int>(std::lower_bound(c.levels.begin(), c.levels.end(), s) - c.levels.begin()));
  return c;
}

// R's poly(x, degree): the centred powers 1, x, ..., x^degree made orthonormal in order
// (Gram-Schmidt, each column's leading coefficient positive, as R's QR-based poly() gives),
// without the constant column.
std::vector<Eigen::VectorXd> OrthogonalPolynomials(const Eigen::VectorXd& x, int degree,
                                                   const std::string& source,
                                                   const std::string& label) {
  const Eigen::VectorXd xc = x.array() - x.mean();
  std::vector<Eigen::VectorXd> q;
  Eigen::VectorXd power = Eigen::VectorXd::Ones(x.size());
  for (int k = 0; k <= degree; ++k) {
    Eigen::VectorXd v = power;
    for (int pass = 0; pass < 2; ++pass)  // reorthogonalised once, for accuracy
      for (const auto& u : q) v -= u.dot(v) * u;
    const double norm = v.norm();
    if (!(norm > 1e-10 * power.norm()))
      throw InputError(source, 0, label, "needs more distinct values than its degree");
    q.push_back(v / norm);
    power = power.cwiseProduct(xc);
  }
  q.erase(q.begin());
  return q;
}

// The formula's variables by label ("x", "log(x)"): columns, and functions of numeric columns
// evaluated (finite or refused, naming the row). The response column is data.y.
class Variables {
 public:
  Variables(const LongTable& data, const LmmFormula& f) : data_(data), f_(f) {
    std::set<std::string> groups;
    for (const auto& r : f.random) groups.insert(r.group_factors.begin(), r.group_factors.end());
    for (const auto& name : f.Columns())
      if (name != f.response && !raw_.count(name))
        raw_.emplace(name, ReadColumn(data, name, groups.count(name) > 0));
  }
  const std::map<std::string, Column>& raw() const { return raw_; }
  std::map<std::string, Column>& cols() { return cols_; }
  void Add(const std::string& label) {
    if (cols_.count(label)) return;
    if (detail::IsColumnName(label)) {
      cols_.emplace(label, raw_.at(label));
      return;
    }
    Column c;
    c.numeric = true;
    std::string inner;
    int degree = 0;
    if (detail::PolyLabel(label, inner, degree)) {
      c.basis = OrthogonalPolynomials(Evaluate(inner), degree, data_.source, label);
    } else {
      const Eigen::VectorXd v = Evaluate(label);
      c.value.assign(v.data(), v.data() + v.size());
    }
    cols_.emplace(label, c);
  }
  Eigen::VectorXd Evaluate(const std::string& label) const {
    const auto n = static_cast<Eigen::Index>(data_.rows());
    Eigen::VectorXd v = detail::EvalExpr(label, [&](const std::string& name) {
      if (name.empty()) return Eigen::VectorXd(Eigen::VectorXd::Zero(n));
      if (name == f_.response)
        return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(data_.y.data(), n));
      const Column& c = raw_.at(name);
      if (!c.numeric)
        throw InputError(data_.source, 0, name,
                         "'" + label + "' needs numbers, but '" + name + "' is a factor");
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(c.value.data(), n));
    });
    for (Eigen::Index i = 0; i < n; ++i)
      if (!std::isfinite(v[i]))
        throw InputError(
            data_.source,
            data_.lines.empty() ? 0 : static_cast<int>(data_.lines[static_cast<std::size_t>(i)]),
            label,
            "is not finite in data row " + std::to_string(i + 1) +
                " (log or sqrt of a value out of range, a division by zero?)");
    return v;
  }

 private:
  const LongTable& data_;
  const LmmFormula& f_;
  std::map<std::string, Column> raw_, cols_;
};

// The fixed-effects matrix X with its column names and terms. R's coding: factor v of term T
// gets contrasts when T without v is in the model.
void FixedEffects(const LmmFormula& f, Variables& vars, std::size_t n, detail::LmmDesign* d) {
  auto& cols = vars.cols();
  std::set<std::set<std::string>> model;
  if (f.intercept) model.insert(std::set<std::string>{});
  for (const auto& t : f.fixed) model.insert(std::set<std::string>(t.begin(), t.end()));
  std::vector<Eigen::VectorXd> xc;
  if (f.intercept) {
    xc.emplace_back(Eigen::VectorXd::Ones(static_cast<Eigen::Index>(n)));
    d->x_names = {"(Intercept)"};
  }
  for (const auto& t : f.fixed) {
    for (const auto& v : t) vars.Add(v);
    detail::LmmDesign::Term term{Join(t), {}};
    const auto before = xc.size();
    auto full = [&](const std::string& v) {
      std::set<std::string> rest(t.begin(), t.end());
      rest.erase(v);
      return model.count(rest) == 0;
    };
    TermColumns(t, cols, n, full, xc, d->x_names);
    for (auto j = before; j < xc.size(); ++j) term.columns.push_back(static_cast<int>(j));
    d->x_terms.push_back(term);
  }
  d->X.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(xc.size()));
  for (std::size_t j = 0; j < xc.size(); ++j) d->X.col(static_cast<Eigen::Index>(j)) = xc[j];
}

// The random-effects matrix Z and its blocks, in lme4's order: decreasing number of grouping
// levels (stable).
void RandomEffects(const LongTable& data, const LmmFormula& f, Variables& vars, std::size_t n,
                   detail::LmmDesign* d) {
  auto& cols = vars.cols();
  std::map<std::string, Column> group_cols;
  for (const auto& r : f.random)
    if (!group_cols.count(r.group)) group_cols.emplace(r.group, GroupColumn(data, r, vars.raw()));
  std::vector<std::size_t> order(f.random.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return group_cols.at(f.random[a].group).levels.size() >
           group_cols.at(f.random[b].group).levels.size();
  });
  std::vector<Eigen::Triplet<double>> trip;
  int offset = 0;
  for (auto i : order) {
    const auto& r = f.random[i];
    std::vector<Eigen::VectorXd> zc;
    detail::LmmDesign::Block b;
    b.group = r.group;
    if (r.intercept) {
      zc.emplace_back(Eigen::VectorXd::Ones(static_cast<Eigen::Index>(n)));
      b.names.emplace_back("(Intercept)");
    }
    for (const auto& t : r.terms)
      for (const auto& v : t) vars.Add(v);
    const bool full = !r.intercept && r.terms.size() == 1 && r.terms[0].size() == 1 &&
                      !cols.at(r.terms[0][0]).numeric;
    for (const auto& t : r.terms) {
      bool has_factor = false;
      for (const auto& v : t) has_factor = has_factor || !cols.at(v).numeric;
      if (!r.intercept && has_factor && !full)
        throw InputError(
            data.source, 0, "formula",
            "a random term without intercept may hold numeric columns or one factor only");
      TermColumns(
          t, cols, n, [full](const std::string&) { return full; }, zc, b.names);
    }
    const Column& g = group_cols.at(r.group);
    b.levels = static_cast<int>(g.levels.size());
    b.p = static_cast<int>(zc.size());
    b.offset = offset;
    for (std::size_t row = 0; row < n; ++row)
      for (int c = 0; c < b.p; ++c) {
        const double v = zc[static_cast<std::size_t>(c)][static_cast<Eigen::Index>(row)];
        if (v != 0.0) trip.emplace_back(static_cast<int>(row), offset + g.level[row] * b.p + c, v);
      }
    offset += b.levels * b.p;
    d->blocks.push_back(b);
  }
  d->Z.resize(static_cast<Eigen::Index>(n), offset);
  d->Z.setFromTriplets(trip.begin(), trip.end());
}

}  // namespace

namespace detail {

LmmDesign BuildLmmDesign(const LongTable& data, const LmmFormula& f) {
  const std::size_t n = data.rows();
  Variables vars(data, f);
  LmmDesign d;
  d.y = detail::IsColumnName(f.response_term) ? Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(
                                                    data.y.data(), static_cast<Eigen::Index>(n)))
                                              : vars.Evaluate(f.response_term);
  FixedEffects(f, vars, n, &d);
  RandomEffects(data, f, vars, n, &d);
  return d;
}

}  // namespace detail
}  // namespace hapticlab::stats
