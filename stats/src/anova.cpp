#include "hapticlab/stats/anova.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/distributions.hpp"

namespace hapticlab::stats {
namespace {

using Eigen::MatrixXd;

// Orthonormal Helmert contrasts for k levels: k x (k-1), columns orthogonal to 1.
MatrixXd Helmert(int k) {
  MatrixXd c = MatrixXd::Zero(k, k - 1);
  for (int j = 1; j < k; ++j) {
    const double norm = std::sqrt(static_cast<double>(j) * (j + 1));
    for (int i = 0; i < j; ++i) c(i, j - 1) = 1.0 / norm;
    c(j, j - 1) = -static_cast<double>(j) / norm;
  }
  return c;
}

MatrixXd Kron(const MatrixXd& a, const MatrixXd& b) {
  MatrixXd r(a.rows() * b.rows(), a.cols() * b.cols());
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    for (Eigen::Index j = 0; j < a.cols(); ++j)
      r.block(i * b.rows(), j * b.cols(), b.rows(), b.cols()) = a(i, j) * b;
  return r;
}

// `nu`: the error df of the multivariate model (N - 1, or N - rank X with between factors);
// `columns`: the number of columns of the multivariate response (all cells of the design),
// which R's mauchly.test uses in one term of its correction (see below).
Sphericity FromCov(const MatrixXd& S, double nu, int columns) {
  Sphericity r;
  const auto p = static_cast<int>(S.rows());
  if (p == 1) {
    r.mauchly_defined = true;
    r.W = 1;
    r.p = r.p_firstorder = 1;
    r.gg = r.hf = 1;
    return r;
  }
  const double tr = S.trace();
  const double ss = (S.array() * S.array()).sum();
  // No variability at all (e.g. identical ratings): nothing to correct.
  r.gg = ss > 0 ? tr * tr / (p * ss) : 1.0;
  // car's Huynh-Feldt (Lecoutre's correction) with error df nu; nu = N - 1 gives the
  // textbook (N p eps - 2) / (p (N - 1 - p eps)).
  r.hf = ss > 0 ? ((nu + 1) * p * r.gg - 2) / (p * (nu - p * r.gg)) : 1.0;
  if (p > nu) {
    // Singular error SSP: no Mauchly test (car/afex); epsilons stay defined.
    r.W = r.p = r.chi2 = r.p_firstorder = std::numeric_limits<double>::quiet_NaN();
    return r;
  }
  r.mauchly_defined = true;
  const double det = S.determinant();
  r.W = det / std::pow(tr / p, p);
  const double log_w = std::log(r.W);
  // R's mauchly.test (stats:::mauchly.test.SSD): Anderson's second-order approximation.
  // R writes `3 * p` with p = ncol(SSD), the response's column count, where the textbook
  // has the term's df; we follow R (the reference analysts compare with). The first-order
  // p-value (SPSS) is reported beside it.
  const double rho = 1 - (2.0 * p * p + p + 2) / (6.0 * p * nu);
  const double w2 = (p + 2.0) * (p - 1) * (p - 2) *
                    (2.0 * p * p * p + 6.0 * p * p + 3.0 * columns + 2) /
                    (288.0 * std::pow(nu * p * rho, 2));
  const double z = -nu * rho * log_w;
  const double f = p * (p + 1) / 2.0 - 1;
  const double pr1 = PchisqUpper(z, f), pr2 = PchisqUpper(z, f + 4);
  // R does not clamp; near-singular covariances can push the approximation past 1.
  r.p = std::clamp(pr1 + w2 * (pr2 - pr1), 0.0, 1.0);
  r.chi2 = z;
  r.p_firstorder = pr1;
  return r;
}

// Sum-to-zero contrasts (R's contr.sum): k x (k-1), identity above a row of -1.
MatrixXd ContrSum(int k) {
  MatrixXd c = MatrixXd::Zero(k, k - 1);
  for (int i = 0; i < k - 1; ++i) c(i, i) = 1;
  c.row(k - 1).setConstant(-1);
  return c;
}

// Non-empty subsets of n factors as bit masks, main effects first, then by size (afex's
// and car's term order: A, B, A:B, C, A:C, ... sorted by order, stable in mask order).
std::vector<int> Terms(int n) {
  std::vector<int> t;
  for (int m = 1; m < (1 << n); ++m) t.push_back(m);
  std::stable_sort(t.begin(), t.end(), [](int a, int b) {
    return __builtin_popcount(static_cast<unsigned>(a)) <
           __builtin_popcount(static_cast<unsigned>(b));
  });
  return t;
}

std::string TermName(int mask, const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t f = 0; f < names.size(); ++f)
    if ((mask >> f) & 1) s += (s.empty() ? "" : ":") + names[f];
  return s;
}

}  // namespace

Sphericity SphericityFromLevelCovariance(const std::vector<std::vector<double>>& S, int n) {
  const auto k = static_cast<Eigen::Index>(S.size());
  MatrixXd m(k, k);
  for (Eigen::Index i = 0; i < k; ++i)
    for (Eigen::Index j = 0; j < k; ++j)
      m(i, j) = S[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
  const MatrixXd c = Helmert(static_cast<int>(k));
  return FromCov(c.transpose() * m * c, n - 1.0, static_cast<int>(k));
}

OneWayResult OneWayAnova(const LongTable& data, const std::string& factor) {
  const auto c = data.Key(factor);
  std::map<std::string, std::vector<double>> groups;
  for (std::size_t i = 0; i < data.rows(); ++i) groups[data.keys[c][i]].push_back(data.y[i]);
  const std::size_t k = groups.size();
  const std::size_t n = data.rows();
  if (k < 2 || n <= k)
    throw InputError(data.source, 0, factor, "one-way ANOVA needs >= 2 groups and N > groups");
  double grand = 0;
  for (double v : data.y) grand += v;
  grand /= static_cast<double>(n);
  OneWayResult r;
  for (const auto& [g, v] : groups) {
    double m = 0;
    for (double x : v) m += x - grand;  // centred first: no cancellation near large offsets
    m /= static_cast<double>(v.size());
    r.SS_between += static_cast<double>(v.size()) * m * m;
    for (double x : v) r.SS_within += (x - grand - m) * (x - grand - m);
  }
  r.df_between = static_cast<double>(k - 1);
  r.df_within = static_cast<double>(n - k);
  r.MS_between = r.SS_between / r.df_between;
  r.MS_within = r.SS_within / r.df_within;
  r.F = r.MS_between / r.MS_within;
  r.p = PfUpper(r.F, r.df_between, r.df_within);
  r.r_squared = r.SS_between / (r.SS_between + r.SS_within);
  r.residual_sd = std::sqrt(r.MS_within);
  return r;
}

RmAnovaResult RmAnova(const LongTable& data, const std::string& subject,
                      const std::vector<std::string>& within,
                      const std::vector<std::string>& between) {
  if (within.empty() && between.empty())
    throw InputError(data.source, 0, "within",
                     "at least one within- or between-subject factor is needed");
  RmAnovaResult res;
  res.factors = within;
  res.between = between;
  for (const auto& b : between)
    if (std::find(within.begin(), within.end(), b) != within.end())
      throw InputError(data.source, 0, b, "given both as a within and as a between factor");
  const std::size_t scol = data.Key(subject);
  std::vector<std::size_t> fcol, bcol;
  std::vector<int> nlev, nblev;
  for (const auto& f : within) {
    fcol.push_back(data.Key(f));
    res.levels.push_back(data.Levels(f));
    if (res.levels.back().size() < 2)
      throw InputError(data.source, 0, f, "a within factor needs at least 2 levels");
    nlev.push_back(static_cast<int>(res.levels.back().size()));
  }
  for (const auto& f : between) {
    bcol.push_back(data.Key(f));
    res.between_levels.push_back(data.Levels(f));
    if (res.between_levels.back().size() < 2)
      throw InputError(data.source, 0, f, "a between factor needs at least 2 levels");
    nblev.push_back(static_cast<int>(res.between_levels.back().size()));
  }
  // A within factor of which every subject has exactly one level is a between factor.
  for (std::size_t f = 0; f < within.size(); ++f) {
    std::map<std::string, std::string> first;
    bool varies = false;
    for (std::size_t r = 0; r < data.rows() && !varies; ++r) {
      const auto [it, fresh] = first.emplace(data.keys[scol][r], data.keys[fcol[f]][r]);
      varies = !fresh && it->second != data.keys[fcol[f]][r];
    }
    if (!varies)
      throw InputError(
          data.source, 0, within[f],
          "'" + within[f] + "' is a between-subjects factor (every " + subject +
              " has one level of it): give it as a between factor, not as a within one");
  }
  int ncells = 1;
  for (int l : nlev) ncells *= l;
  int ngroups = 1;
  for (int l : nblev) ngroups *= l;
  auto level_index = [](const std::vector<std::string>& lv, const std::string& v) {
    return static_cast<int>(std::lower_bound(lv.begin(), lv.end(), v) - lv.begin());
  };
  // Average repetitions per subject x cell; a NaN response leaves the cell unobserved.
  struct Acc {
    std::vector<std::pair<double, int>> cell;
    std::vector<std::size_t> missing_rows;
    int group = -1;
  };
  std::map<std::string, Acc> acc;
  for (std::size_t r = 0; r < data.rows(); ++r) {
    int cell = 0;
    for (std::size_t f = 0; f < within.size(); ++f)
      cell = cell * nlev[f] + level_index(res.levels[f], data.keys[fcol[f]][r]);
    int group = 0;
    for (std::size_t f = 0; f < between.size(); ++f)
      group = group * nblev[f] + level_index(res.between_levels[f], data.keys[bcol[f]][r]);
    const std::string& s = data.keys[scol][r];
    auto& a = acc[s];
    if (a.cell.empty()) a.cell.assign(static_cast<std::size_t>(ncells), {0.0, 0});
    if (a.group >= 0 && a.group != group) {
      std::size_t f = 0;
      // Name the between factor that differs.
      for (std::size_t g = 0; g < between.size(); ++g) {
        int stride = 1;
        for (std::size_t h = g + 1; h < between.size(); ++h) stride *= nblev[h];
        if ((a.group / stride) % nblev[g] != (group / stride) % nblev[g]) f = g;
      }
      throw InputError(data.source, 0, between[f],
                       "'" + between[f] + "' varies within " + subject + " " + s +
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
  auto cell_name = [&](int c) {
    std::string s;
    for (int f = static_cast<int>(within.size()) - 1; f >= 0; --f) {
      const auto uf = static_cast<std::size_t>(f);
      s = within[uf] + "=" + res.levels[uf][static_cast<std::size_t>(c % nlev[uf])] +
          (s.empty() ? "" : ",") + s;
      c /= nlev[uf];
    }
    return s;
  };
  res.group_sizes.assign(static_cast<std::size_t>(ngroups), 0);
  for (const auto& [s, a] : acc) {
    std::vector<std::string> missing;
    for (int c = 0; c < ncells; ++c)
      if (a.cell[static_cast<std::size_t>(c)].second == 0) missing.push_back(cell_name(c));
    if (!missing.empty() || !a.missing_rows.empty()) {
      std::string why;
      if (!missing.empty()) {
        why = "no rating for ";
        for (std::size_t i = 0; i < missing.size(); ++i) why += (i ? "; " : "") + missing[i];
      }
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
  for (int g = 0; g < ngroups; ++g)
    if (res.group_sizes[static_cast<std::size_t>(g)] == 0) {
      std::string name;
      int c = g;
      for (int f = static_cast<int>(between.size()) - 1; f >= 0; --f) {
        const auto uf = static_cast<std::size_t>(f);
        name = between[uf] + "=" + res.between_levels[uf][static_cast<std::size_t>(c % nblev[uf])] +
               (name.empty() ? "" : ",") + name;
        c /= nblev[uf];
      }
      throw InputError(data.source, 0, between.empty() ? subject : between[0],
                       "no " + subject + " with every cell observed in the between cell " + name);
    }
  if (n <= ngroups)
    throw InputError(data.source, 0, subject,
                     "no error degrees of freedom: " + std::to_string(n) + " subjects in " +
                         std::to_string(ngroups) + " between cells");
  MatrixXd Y(n, ncells);
  for (int s = 0; s < n; ++s)
    for (int c = 0; c < ncells; ++c)
      Y(s, c) = res.cells[static_cast<std::size_t>(s)][static_cast<std::size_t>(c)];

  // Between design: intercept, then every between term (sum-to-zero codes, full factorial).
  const int nb = static_cast<int>(between.size());
  const std::vector<int> bterms = Terms(nb);
  std::vector<std::pair<Eigen::Index, Eigen::Index>> bcols;  // first column and count per term
  MatrixXd X(n, ngroups);
  {
    // Level indices of each between cell.
    auto levels_of = [&](int g) {
      std::vector<int> l(static_cast<std::size_t>(nb));
      for (int f = nb - 1; f >= 0; --f) {
        l[static_cast<std::size_t>(f)] = g % nblev[static_cast<std::size_t>(f)];
        g /= nblev[static_cast<std::size_t>(f)];
      }
      return l;
    };
    for (int s = 0; s < n; ++s) {
      const auto l = levels_of(res.subject_group[static_cast<std::size_t>(s)]);
      X(s, 0) = 1;
      Eigen::Index col = 1;
      for (int mask : bterms) {
        MatrixXd row = MatrixXd::Ones(1, 1);
        for (int f = 0; f < nb; ++f)
          if ((mask >> f) & 1) {
            const MatrixXd c = ContrSum(nblev[static_cast<std::size_t>(f)]);
            row = Kron(row, c.row(l[static_cast<std::size_t>(f)]));
          }
        X.block(s, col, 1, row.cols()) = row;
        if (s == 0) bcols.emplace_back(col, row.cols());
        col += row.cols();
      }
    }
  }
  const MatrixXd XtXi = (X.transpose() * X).inverse();
  res.error_df = n - ngroups;
  const double nu = res.error_df;

  // Within terms: the intercept term (mask 0: between effects only) then every within term.
  const int nf = static_cast<int>(within.size());
  std::vector<int> wterms{0};
  for (int m : Terms(nf)) wterms.push_back(m);
  for (int wmask : wterms) {
    MatrixXd P = MatrixXd::Ones(1, 1);
    for (int f = 0; f < nf; ++f) {
      const bool in = (wmask >> f) & 1;
      P = Kron(P, in ? Helmert(nlev[static_cast<std::size_t>(f)])
                     : MatrixXd::Constant(nlev[static_cast<std::size_t>(f)], 1,
                                          1.0 / std::sqrt(nlev[static_cast<std::size_t>(f)])));
    }
    const MatrixXd Z = Y * P;
    const MatrixXd B = XtXi * (X.transpose() * Z);
    const MatrixXd E = Z - X * B;
    const MatrixXd SSPE = E.transpose() * E;
    const Sphericity sp = FromCov(SSPE / nu, nu, ncells);
    // Between terms crossed with this within term; mask 0 is the within term alone.
    std::vector<int> bt;
    if (wmask != 0) bt.push_back(0);
    for (int m : bterms) bt.push_back(m);
    for (int bmask : bt) {
      Eigen::Index c0 = 0, nc = 1;
      if (bmask != 0) {
        const auto it = std::find(bterms.begin(), bterms.end(), bmask) - bterms.begin();
        std::tie(c0, nc) = bcols[static_cast<std::size_t>(it)];
      }
      const MatrixXd LB = B.middleRows(c0, nc);
      const MatrixXd M = XtXi.block(c0, c0, nc, nc);
      AnovaEffect e;
      const std::string bn = TermName(bmask, between), wn = TermName(wmask, within);
      e.effect = bn.empty() ? wn : wn.empty() ? bn : bn + ":" + wn;
      e.df1 = static_cast<double>(P.cols() * nc);
      e.df2 = static_cast<double>(P.cols()) * nu;
      e.SS = (LB.transpose() * M.ldlt().solve(LB)).trace();
      e.SS_error = SSPE.trace();
      e.MSE = e.SS_error / e.df2;
      e.F = (e.SS / e.df1) / e.MSE;
      e.p = PfUpper(e.F, e.df1, e.df2);
      e.pes = e.SS / (e.SS + e.SS_error);
      if (wmask == 0) {
        // Between-subjects term: no sphericity question (afex prints nothing).
        const double nan = std::numeric_limits<double>::quiet_NaN();
        e.between_only = true;
        e.mauchly_defined = false;
        e.mauchly_W = e.mauchly_p = e.mauchly_chi2 = e.mauchly_p_firstorder = nan;
        e.gg_epsilon = e.hf_epsilon = 1;
        e.p_gg = e.p_hf = e.p;
        res.effects.push_back(e);
        continue;
      }
      const double df_w = static_cast<double>(P.cols());
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
      res.effects.push_back(e);
    }
  }
  return res;
}

Correction ParseCorrection(const std::string& name, const std::string& source,
                           const std::string& field) {
  if (name == "GG") return Correction::kGG;
  if (name == "HF") return Correction::kHF;
  if (name == "none") return Correction::kNone;
  throw InputError(source, 0, field,
                   "expected GG (Greenhouse-Geisser, afex's default), HF (Huynh-Feldt) or none, "
                   "got '" +
                       name + "'");
}

const char* CorrectionName(Correction c) {
  return c == Correction::kGG ? "GG" : c == Correction::kHF ? "HF" : "none";
}

double UsedEpsilon(const AnovaEffect& e, Correction c) {
  if (e.between_only || c == Correction::kNone) return 1;
  return c == Correction::kGG ? e.gg_epsilon : e.hf_epsilon_used;
}

double UsedP(const AnovaEffect& e, Correction c) {
  if (e.between_only || c == Correction::kNone) return e.p;
  return c == Correction::kGG ? e.p_gg : e.p_hf;
}

std::vector<double> AnovaResiduals(const RmAnovaResult& a) {
  const std::size_t n = a.cells.size(), cells = n ? a.cells[0].size() : 0;
  // Cell means per between group (the fitted values of the multivariate lm).
  std::map<int, std::vector<double>> sum;
  std::map<int, int> count;
  for (std::size_t s = 0; s < n; ++s) {
    const int g = s < a.subject_group.size() ? a.subject_group[s] : 0;
    auto& v = sum[g];
    v.resize(cells, 0.0);
    for (std::size_t c = 0; c < cells; ++c) v[c] += a.cells[s][c];
    count[g] += 1;
  }
  std::vector<double> r;
  r.reserve(n * cells);
  for (std::size_t s = 0; s < n; ++s) {
    const int g = s < a.subject_group.size() ? a.subject_group[s] : 0;
    for (std::size_t c = 0; c < cells; ++c)
      r.push_back(a.cells[s][c] - sum[g][c] / static_cast<double>(count[g]));
  }
  return r;
}

}  // namespace hapticlab::stats
