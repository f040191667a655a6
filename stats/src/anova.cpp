#include "hapticlab/stats/anova.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

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
    for (Eigen::Index j = 0; j < a.cols(); ++j) r.block(i * b.rows(), j * b.cols(), b.rows(), b.cols()) = a(i, j) * b;
  return r;
}

// `columns`: the number of columns of the multivariate response (all cells of the design),
// which R's mauchly.test uses in one term of its correction (see below).
Sphericity FromCov(const MatrixXd& S, int n, int columns) {
  Sphericity r;
  const auto p = static_cast<int>(S.rows());
  const double nu = n - 1;  // error df of the multivariate model
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
  r.hf = ss > 0 ? (n * p * r.gg - 2) / (p * (n - 1 - p * r.gg)) : 1.0;
  if (p > n - 1) {
    // Singular error SSP: no Mauchly test (car/afex); epsilons stay defined.
    r.W = r.p = r.chi2 = r.p_firstorder = std::numeric_limits<double>::quiet_NaN();
    return r;
  }
  r.mauchly_defined = true;
  const double det = S.determinant();
  r.W = det / std::pow(tr / p, p);
  const double logW = std::log(r.W);
  // R's mauchly.test (stats:::mauchly.test.SSD): Anderson's second-order approximation.
  // R writes `3 * p` with p = ncol(SSD), the response's column count, where the textbook
  // has the term's df; we follow R (the reference analysts compare with). The first-order
  // p-value (SPSS) is reported beside it.
  const double rho = 1 - (2.0 * p * p + p + 2) / (6.0 * p * nu);
  const double w2 = (p + 2.0) * (p - 1) * (p - 2) * (2.0 * p * p * p + 6.0 * p * p + 3.0 * columns + 2) /
                    (288.0 * std::pow(nu * p * rho, 2));
  const double z = -nu * rho * logW;
  const double f = p * (p + 1) / 2.0 - 1;
  const double pr1 = PchisqUpper(z, f), pr2 = PchisqUpper(z, f + 4);
  // R does not clamp; near-singular covariances can push the approximation past 1.
  r.p = std::clamp(pr1 + w2 * (pr2 - pr1), 0.0, 1.0);
  r.chi2 = z;
  r.p_firstorder = pr1;
  return r;
}

}  // namespace

Sphericity SphericityFromLevelCovariance(const std::vector<std::vector<double>>& S, int n) {
  const auto k = static_cast<Eigen::Index>(S.size());
  MatrixXd m(k, k);
  for (Eigen::Index i = 0; i < k; ++i)
    for (Eigen::Index j = 0; j < k; ++j) m(i, j) = S[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
  const MatrixXd c = Helmert(static_cast<int>(k));
  return FromCov(c.transpose() * m * c, n, static_cast<int>(k));
}

OneWayResult OneWayAnova(const LongTable& data, const std::string& factor) {
  const auto c = data.Key(factor);
  std::map<std::string, std::vector<double>> groups;
  for (std::size_t i = 0; i < data.rows(); ++i) groups[data.keys[c][i]].push_back(data.y[i]);
  const std::size_t k = groups.size();
  const std::size_t n = data.rows();
  if (k < 2 || n <= k) throw InputError(data.source, 0, factor, "one-way ANOVA needs >= 2 groups and N > groups");
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
                      const std::vector<std::string>& within) {
  if (within.empty()) throw InputError(data.source, 0, "within", "at least one within-subject factor is needed");
  RmAnovaResult res;
  res.factors = within;
  std::vector<std::size_t> fcol;
  std::vector<int> nlev;
  for (const auto& f : within) {
    fcol.push_back(data.Key(f));
    res.levels.push_back(data.Levels(f));
    if (res.levels.back().size() < 2)
      throw InputError(data.source, 0, f, "a within factor needs at least 2 levels");
    nlev.push_back(static_cast<int>(res.levels.back().size()));
  }
  int ncells = 1;
  for (int l : nlev) ncells *= l;
  const std::size_t scol = data.Key(subject);
  // Average repetitions per subject x cell.
  std::map<std::string, std::vector<std::pair<double, int>>> acc;
  for (std::size_t r = 0; r < data.rows(); ++r) {
    int cell = 0;
    for (std::size_t f = 0; f < within.size(); ++f) {
      const auto& lv = res.levels[f];
      const int idx = static_cast<int>(std::lower_bound(lv.begin(), lv.end(), data.keys[fcol[f]][r]) - lv.begin());
      cell = cell * nlev[f] + idx;
    }
    auto& v = acc[data.keys[scol][r]];
    if (v.empty()) v.assign(static_cast<std::size_t>(ncells), {0.0, 0});
    v[static_cast<std::size_t>(cell)].first += data.y[r];
    v[static_cast<std::size_t>(cell)].second += 1;
  }
  for (const auto& [s, v] : acc) {
    const bool complete = std::all_of(v.begin(), v.end(), [](const auto& c) { return c.second > 0; });
    if (!complete) {
      res.dropped_subjects.push_back(s);
      continue;
    }
    res.subjects.push_back(s);
    std::vector<double> row;
    for (const auto& c : v) row.push_back(c.first / c.second);
    res.cells.push_back(std::move(row));
  }
  const int n = static_cast<int>(res.subjects.size());
  if (n < 2) throw InputError(data.source, 0, subject, "fewer than 2 subjects with every cell observed");
  MatrixXd Y(n, ncells);
  for (int s = 0; s < n; ++s)
    for (int c = 0; c < ncells; ++c) Y(s, c) = res.cells[static_cast<std::size_t>(s)][static_cast<std::size_t>(c)];

  // Effects: every non-empty subset of factors, main effects first (afex's order).
  const int nf = static_cast<int>(within.size());
  std::vector<int> subsets;
  for (int m = 1; m < (1 << nf); ++m) subsets.push_back(m);
  std::stable_sort(subsets.begin(), subsets.end(),
                   [](int a, int b) { return __builtin_popcount(static_cast<unsigned>(a)) < __builtin_popcount(static_cast<unsigned>(b)); });
  for (int mask : subsets) {
    MatrixXd P = MatrixXd::Ones(1, 1);
    std::string name;
    for (int f = 0; f < nf; ++f) {
      const bool in = (mask >> f) & 1;
      P = Kron(P, in ? Helmert(nlev[static_cast<std::size_t>(f)])
                     : MatrixXd::Constant(nlev[static_cast<std::size_t>(f)], 1, 1.0 / std::sqrt(nlev[static_cast<std::size_t>(f)])));
      if (in) name += (name.empty() ? "" : ":") + within[static_cast<std::size_t>(f)];
    }
    const MatrixXd Z = Y * P;
    const Eigen::RowVectorXd zbar = Z.colwise().mean();
    const MatrixXd Zc = Z.rowwise() - zbar;
    AnovaEffect e;
    e.effect = name;
    e.df1 = static_cast<double>(P.cols());
    e.df2 = e.df1 * (n - 1);
    e.SS = n * zbar.squaredNorm();
    e.SS_error = Zc.squaredNorm();
    e.MSE = e.SS_error / e.df2;
    e.F = (e.SS / e.df1) / e.MSE;
    e.p = PfUpper(e.F, e.df1, e.df2);
    e.pes = e.SS / (e.SS + e.SS_error);
    const MatrixXd S = Zc.transpose() * Zc / (n - 1);
    const Sphericity sp = FromCov(S, n, ncells);
    e.mauchly_defined = sp.mauchly_defined;
    e.mauchly_W = sp.W;
    e.mauchly_p = sp.p;
    e.mauchly_chi2 = sp.chi2;
    e.mauchly_p_firstorder = sp.p_firstorder;
    e.gg_epsilon = sp.gg;
    e.hf_epsilon = sp.hf;
    e.p_gg = PfUpper(e.F, e.df1 * sp.gg, e.df2 * sp.gg);
    // Used epsilon: min(1, eps) as R; with very few subjects the Huynh-Feldt formula can fall
    // below the theoretical floor 1/df1 (even below 0), where R returns NaN: we floor it.
    // (n = 2 makes it 0/0: then Greenhouse-Geisser is used.)
    const double hf = std::clamp(std::isfinite(sp.hf) ? sp.hf : sp.gg, 1.0 / e.df1, 1.0);
    e.p_hf = PfUpper(e.F, e.df1 * hf, e.df2 * hf);
    res.effects.push_back(e);
  }
  return res;
}

}  // namespace hapticlab::stats
