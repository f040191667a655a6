// The repeated-measures ANOVA with between factors (anova.hpp's RmAnova), as afex's aov_ez
// computes it: repetitions averaged per subject x cell, subjects with a missing cell dropped
// and named, then per within term the multivariate linear model of the transformed cell
// means on the between design (type 3 sums of squares with sum-to-zero codes), with Mauchly's
// test and the Greenhouse-Geisser and Huynh-Feldt corrections.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

#include "anova_internal.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/distributions.hpp"

namespace hapticlab::stats {
namespace {

using namespace anova_internal;

// The factors' columns and level counts; cells over the within factors and groups over the
// between factors are numbered with the last factor fastest.
struct Layout {
  std::size_t subject_col = 0;
  std::vector<std::size_t> wcol, bcol;
  std::vector<int> nlev, nblev;
  int ncells = 1, ngroups = 1;
};

int LevelIndex(const std::vector<std::string>& levels, const std::string& v) {
  return static_cast<int>(std::lower_bound(levels.begin(), levels.end(), v) - levels.begin());
}

// "f=a,g=b" of cell index c over factors with `counts` levels (last factor fastest).
std::string CombinationName(int c, const std::vector<std::string>& factors,
                            const std::vector<std::vector<std::string>>& levels,
                            const std::vector<int>& counts) {
  std::string s;
  for (int f = static_cast<int>(factors.size()) - 1; f >= 0; --f) {
    const auto uf = static_cast<std::size_t>(f);
    s = factors[uf] + "=" + levels[uf][static_cast<std::size_t>(c % counts[uf])] +
        (s.empty() ? "" : ",") + s;
    c /= counts[uf];
  }
  return s;
}

// Reads the factors' levels into `res` and checks them: 2+ levels each, no factor both within
// and between, and every within factor varying within some subject.
Layout ReadFactors(const LongTable& data, const std::string& subject, RmAnovaResult& res) {
  const auto& within = res.factors;
  const auto& between = res.between;
  if (within.empty() && between.empty())
    throw InputError(data.source, 0, "within",
                     "at least one within- or between-subject factor is needed");
  for (const auto& b : between)
    if (std::find(within.begin(), within.end(), b) != within.end())
      throw InputError(data.source, 0, b, "given both as a within and as a between factor");
  Layout l;
  l.subject_col = data.Key(subject);
  for (const auto& f : within) {
    l.wcol.push_back(data.Key(f));
    res.levels.push_back(data.Levels(f));
    if (res.levels.back().size() < 2)
      throw InputError(data.source, 0, f, "a within factor needs at least 2 levels");
    l.nlev.push_back(static_cast<int>(res.levels.back().size()));
    l.ncells *= l.nlev.back();
  }
  for (const auto& f : between) {
    l.bcol.push_back(data.Key(f));
    res.between_levels.push_back(data.Levels(f));
    if (res.between_levels.back().size() < 2)
      throw InputError(data.source, 0, f, "a between factor needs at least 2 levels");
    l.nblev.push_back(static_cast<int>(res.between_levels.back().size()));
    l.ngroups *= l.nblev.back();
  }
  // A within factor of which every subject has exactly one level is a between factor.
  for (std::size_t f = 0; f < within.size(); ++f) {
    std::map<std::string, std::string> first;
    bool varies = false;
    for (std::size_t r = 0; r < data.rows() && !varies; ++r) {
      const auto [it, fresh] = first.emplace(data.keys[l.subject_col][r], data.keys[l.wcol[f]][r]);
      varies = !fresh && it->second != data.keys[l.wcol[f]][r];
    }
    if (!varies)
      throw InputError(
          data.source, 0, within[f],
          "'" + within[f] + "' is a between-subjects factor (every " + subject +
              " has one level of it): give it as a between factor, not as a within one");
  }
  return l;
}

// Per subject: the sum and count of each cell (a NaN response poisons its cell), the rows of
// missing responses, and the between group.
struct SubjectCells {
  std::vector<std::pair<double, int>> cell;
  std::vector<std::size_t> missing_rows;
  int group = -1;
};

std::map<std::string, SubjectCells> Accumulate(const LongTable& data, const std::string& subject,
                                               const RmAnovaResult& res, const Layout& l) {
  std::map<std::string, SubjectCells> acc;
  for (std::size_t r = 0; r < data.rows(); ++r) {
    int cell = 0;
    for (std::size_t f = 0; f < l.wcol.size(); ++f)
      cell = cell * l.nlev[f] + LevelIndex(res.levels[f], data.keys[l.wcol[f]][r]);
    int group = 0;
    for (std::size_t f = 0; f < l.bcol.size(); ++f)
      group = group * l.nblev[f] + LevelIndex(res.between_levels[f], data.keys[l.bcol[f]][r]);
    const std::string& s = data.keys[l.subject_col][r];
    auto& a = acc[s];
    if (a.cell.empty()) a.cell.assign(static_cast<std::size_t>(l.ncells), {0.0, 0});
    if (a.group >= 0 && a.group != group) {
      std::size_t f = 0;  // the between factor that differs
      for (std::size_t g = 0; g < l.nblev.size(); ++g) {
        int stride = 1;
        for (std::size_t h = g + 1; h < l.nblev.size(); ++h) stride *= l.nblev[h];
        if ((a.group / stride) % l.nblev[g] != (group / stride) % l.nblev[g]) f = g;
      }
      const auto& name = res.between[f];
      throw InputError(data.source, 0, name,
                       "'" + name + "' varies within " + subject + " " + s +
                           ": a between factor must be constant per " + subject +
                           " (give it as a within factor)");
    }
    a.group = group;
    auto& c = a.cell[static_cast<std::size_t>(cell)];
    if (std::isnan(data.y[r])) {
      a.missing_rows.push_back(r);
      c.second = -(1 << 20);  // poisons the cell
      continue;
    }
    c.first += data.y[r];
    c.second += 1;
  }
  return acc;
}

// Why a subject is dropped: the cells without a rating and the lines of missing responses.
std::string DropReason(const LongTable& data, const RmAnovaResult& res, const Layout& l,
                       const SubjectCells& a) {
  std::string why;
  for (int c = 0; c < l.ncells; ++c)
    if (a.cell[static_cast<std::size_t>(c)].second == 0)
      why += (why.empty() ? "no rating for " : "; ") +
             CombinationName(c, res.factors, res.levels, l.nlev);
  if (!a.missing_rows.empty()) {
    why += why.empty() ? "" : "; ";
    why += "missing " + (data.y_name.empty() ? std::string("response") : data.y_name);
    for (std::size_t i = 0; i < a.missing_rows.size(); ++i) {
      const std::size_t r = a.missing_rows[i];
      why += (i ? ", " : " at ") + (r < data.lines.size()
                                        ? data.source + ":" + std::to_string(data.lines[r])
                                        : "row " + std::to_string(r + 1));
    }
  }
  return why;
}

// Keeps the subjects with every cell observed (cell means into res.cells), names the others,
// and checks that every between cell keeps a subject and error df remain.
void KeepCompleteSubjects(const LongTable& data, const std::string& subject,
                          const std::map<std::string, SubjectCells>& acc, const Layout& l,
                          RmAnovaResult& res) {
  res.group_sizes.assign(static_cast<std::size_t>(l.ngroups), 0);
  for (const auto& [s, a] : acc) {
    const std::string why = DropReason(data, res, l, a);
    if (!why.empty()) {
      res.dropped_subjects.push_back(s);
      res.dropped_reasons.push_back(why);
      continue;
    }
    res.subjects.push_back(s);
    res.subject_group.push_back(a.group);
    res.group_sizes[static_cast<std::size_t>(a.group)] += 1;
    std::vector<double> row;
    for (const auto& c : a.cell) row.push_back(c.first / c.second);
    res.cells.push_back(std::move(row));
  }
  const int n = static_cast<int>(res.subjects.size());
  if (n < 2)
    throw InputError(data.source, 0, subject, "fewer than 2 subjects with every cell observed");
  for (int g = 0; g < l.ngroups; ++g)
    if (res.group_sizes[static_cast<std::size_t>(g)] == 0)
      throw InputError(data.source, 0, res.between.empty() ? subject : res.between[0],
                       "no " + subject + " with every cell observed in the between cell " +
                           CombinationName(g, res.between, res.between_levels, l.nblev));
  if (n <= l.ngroups)
    throw InputError(data.source, 0, subject,
                     "no error degrees of freedom: " + std::to_string(n) + " subjects in " +
                         std::to_string(l.ngroups) + " between cells");
}

// The between design: intercept, then every between term (sum-to-zero codes, full
// factorial); `columns` gets each term's first column and count.
MatrixXd BetweenDesign(const RmAnovaResult& res, const Layout& l, const std::vector<int>& bterms,
                       std::vector<std::pair<Eigen::Index, Eigen::Index>>& columns) {
  const int n = static_cast<int>(res.subjects.size());
  const int nb = static_cast<int>(l.nblev.size());
  MatrixXd X(n, l.ngroups);
  for (int s = 0; s < n; ++s) {
    std::vector<int> lv(static_cast<std::size_t>(nb));  // level indices of the subject's group
    for (int f = nb - 1, g = res.subject_group[static_cast<std::size_t>(s)]; f >= 0; --f) {
      lv[static_cast<std::size_t>(f)] = g % l.nblev[static_cast<std::size_t>(f)];
      g /= l.nblev[static_cast<std::size_t>(f)];
    }
    X(s, 0) = 1;
    Eigen::Index col = 1;
    for (int mask : bterms) {
      MatrixXd row = MatrixXd::Ones(1, 1);
      for (int f = 0; f < nb; ++f)
        if ((mask >> f) & 1)
          row = Kron(
              row,
              ContrSum(l.nblev[static_cast<std::size_t>(f)]).row(lv[static_cast<std::size_t>(f)]));
      X.block(s, col, 1, row.cols()) = row;
      if (s == 0) columns.emplace_back(col, row.cols());
      col += row.cols();
    }
  }
  return X;
}

// Mauchly's test and the corrected p values of a within effect.
void SetSphericity(AnovaEffect& e, const Sphericity& sp, double df_w) {
  e.mauchly_defined = sp.mauchly_defined;
  e.mauchly_W = sp.W;
  e.mauchly_p = sp.p;
  e.mauchly_chi2 = sp.chi2;
  e.mauchly_p_firstorder = sp.p_firstorder;
  e.gg_epsilon = sp.gg;
  e.hf_epsilon = sp.hf;
  e.p_gg = PfUpper(e.F, e.df1 * sp.gg, e.df2 * sp.gg);
  // Used epsilon: min(1, eps) as R; with very few subjects the Huynh-Feldt formula can fall
  // below the theoretical floor 1/df (even below 0), where R returns NaN: we floor it.
  // (n = 2 makes it 0/0: then Greenhouse-Geisser is used.)
  const double hf = std::clamp(std::isfinite(sp.hf) ? sp.hf : sp.gg, 1.0 / df_w, 1.0);
  e.hf_epsilon_used = hf;
  e.p_hf = PfUpper(e.F, e.df1 * hf, e.df2 * hf);
}

// The multivariate model of the cell means Y on the between design X.
struct BetweenModel {
  MatrixXd Y, X, XtXi;
  std::vector<int> bterms;
  std::vector<std::pair<Eigen::Index, Eigen::Index>> bcols;
};

// One within term (mask 0: the between effects alone) and its interactions with the between
// terms, appended to res.effects.
void WithinTerm(int wmask, const BetweenModel& m, const Layout& l, RmAnovaResult& res) {
  const int nf = static_cast<int>(l.nlev.size());
  MatrixXd P = MatrixXd::Ones(1, 1);
  for (int f = 0; f < nf; ++f) {
    const int k = l.nlev[static_cast<std::size_t>(f)];
    P = Kron(P, (wmask >> f) & 1 ? Helmert(k) : MatrixXd::Constant(k, 1, 1.0 / std::sqrt(k)));
  }
  const double nu = res.error_df;
  const MatrixXd Z = m.Y * P;
  const MatrixXd B = m.XtXi * (m.X.transpose() * Z);
  const MatrixXd E = Z - m.X * B;
  const MatrixXd SSPE = E.transpose() * E;
  const Sphericity sp = FromCov(SSPE / nu, nu, l.ncells);
  std::vector<int> bt;  // between terms crossed with this within term; 0: the term alone
  if (wmask != 0) bt.push_back(0);
  bt.insert(bt.end(), m.bterms.begin(), m.bterms.end());
  for (int bmask : bt) {
    Eigen::Index c0 = 0, nc = 1;
    if (bmask != 0) {
      const auto it = std::find(m.bterms.begin(), m.bterms.end(), bmask) - m.bterms.begin();
      std::tie(c0, nc) = m.bcols[static_cast<std::size_t>(it)];
    }
    const MatrixXd LB = B.middleRows(c0, nc);
    AnovaEffect e;
    const std::string bn = TermName(bmask, res.between), wn = TermName(wmask, res.factors);
    e.effect = bn.empty() ? wn : wn.empty() ? bn : bn + ":" + wn;
    e.df1 = static_cast<double>(P.cols() * nc);
    e.df2 = static_cast<double>(P.cols()) * nu;
    e.SS = (LB.transpose() * m.XtXi.block(c0, c0, nc, nc).ldlt().solve(LB)).trace();
    e.SS_error = SSPE.trace();
    e.MSE = e.SS_error / e.df2;
    e.F = (e.SS / e.df1) / e.MSE;
    e.p = PfUpper(e.F, e.df1, e.df2);
    e.pes = e.SS / (e.SS + e.SS_error);
    if (wmask == 0) {  // between-subjects term: no sphericity question (afex prints nothing)
      const double nan = std::numeric_limits<double>::quiet_NaN();
      e.between_only = true;
      e.mauchly_defined = false;
      e.mauchly_W = e.mauchly_p = e.mauchly_chi2 = e.mauchly_p_firstorder = nan;
      e.gg_epsilon = e.hf_epsilon = 1;
      e.p_gg = e.p_hf = e.p;
    } else {
      SetSphericity(e, sp, static_cast<double>(P.cols()));
    }
    res.effects.push_back(e);
  }
}

}  // namespace

RmAnovaResult RmAnova(const LongTable& data, const std::string& subject,
                      const std::vector<std::string>& within,
                      const std::vector<std::string>& between) {
  RmAnovaResult res;
  res.factors = within;
  res.between = between;
  const Layout l = ReadFactors(data, subject, res);
  KeepCompleteSubjects(data, subject, Accumulate(data, subject, res, l), l, res);
  const int n = static_cast<int>(res.subjects.size());
  BetweenModel m;
  m.Y.resize(n, l.ncells);
  for (int s = 0; s < n; ++s)
    for (int c = 0; c < l.ncells; ++c)
      m.Y(s, c) = res.cells[static_cast<std::size_t>(s)][static_cast<std::size_t>(c)];
  m.bterms = Terms(static_cast<int>(between.size()));
  m.X = BetweenDesign(res, l, m.bterms, m.bcols);
  m.XtXi = (m.X.transpose() * m.X).inverse();
  res.error_df = n - l.ngroups;
  // The intercept term (mask 0: between effects only), then every within term.
  WithinTerm(0, m, l, res);
  for (int wmask : Terms(static_cast<int>(within.size()))) WithinTerm(wmask, m, l, res);
  return res;
}

}  // namespace hapticlab::stats
