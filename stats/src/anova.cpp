#include "hapticlab/stats/anova.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

#include "anova_internal.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/distributions.hpp"

namespace hapticlab::stats {
namespace anova_internal {

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
  if (!(det > 0)) {
    // A contrast without error variance (e.g. two levels a constant apart in every subject):
    // W = 0, and R's mauchly.test gives chi2 = Inf, p = 0.
    r.W = 0;
    r.chi2 = std::numeric_limits<double>::infinity();
    r.p = r.p_firstorder = 0;
    return r;
  }
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

}  // namespace anova_internal

using namespace anova_internal;

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
