#include "hapticlab/stats/tukey.hpp"

#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/distributions.hpp"

namespace hapticlab::stats {
namespace {

// All pairs of a family share k and df: one TukeyFamily serves them all.
void Fill(TukeyPair& p, const TukeyFamily& fam, double q_crit) {
  p.q = std::abs(p.diff) / (p.se / std::numbers::sqrt2);
  p.p_adj = fam.Upper(p.q);
  const double half = q_crit / std::numbers::sqrt2 * p.se;
  p.lwr = p.diff - half;
  p.upr = p.diff + half;
}

// Every pair (levels[j] - levels[i], j > i) of the family: `diff_se(i, j, &diff, &se)` gives
// the pair's estimate and standard error; r.k and r.df must be set.
template <class DiffSe>
void AddPairs(TukeyResult& r, const std::vector<std::string>& levels, double conf, DiffSe diff_se) {
  const TukeyFamily fam(r.k, r.df);
  const double q_crit = fam.Quantile(conf);
  for (std::size_t i = 0; i < levels.size(); ++i)
    for (std::size_t j = i + 1; j < levels.size(); ++j) {
      TukeyPair p;
      p.a = levels[j];
      p.b = levels[i];
      diff_se(i, j, &p.diff, &p.se);
      p.df = r.df;
      Fill(p, fam, q_crit);
      r.pairs.push_back(p);
    }
}

}  // namespace

TukeyResult TukeyBetween(const LongTable& data, const std::string& factor, double conf) {
  TukeyResult r;
  r.method = "between";
  r.factor = factor;
  const auto levels = data.Levels(factor);
  const auto c = data.Key(factor);
  r.k = static_cast<int>(levels.size());
  if (r.k < 2) throw InputError(data.source, 0, factor, "Tukey needs at least 2 groups");
  std::map<std::string, std::pair<double, int>> sum;
  for (std::size_t i = 0; i < data.rows(); ++i) {
    auto& s = sum[data.keys[c][i]];
    s.first += data.y[i];
    s.second += 1;
  }
  double ssw = 0;
  for (std::size_t i = 0; i < data.rows(); ++i) {
    const auto& s = sum[data.keys[c][i]];
    const double d = data.y[i] - s.first / s.second;
    ssw += d * d;
  }
  r.df = static_cast<double>(data.rows()) - r.k;
  if (!(r.df > 0)) throw InputError(data.source, 0, factor, "no error degrees of freedom left");
  r.mse = ssw / r.df;
  AddPairs(r, levels, conf, [&](std::size_t i, std::size_t j, double* diff, double* se) {
    const auto& si = sum[levels[i]];
    const auto& sj = sum[levels[j]];
    *diff = sj.first / sj.second - si.first / si.second;
    *se = std::sqrt(r.mse * (1.0 / si.second + 1.0 / sj.second));
  });
  return r;
}

namespace {

// The between cells of a (mixed) ANOVA's subjects: one cell when it has no between factors.
struct BetweenCells {
  const RmAnovaResult& a;
  std::size_t n = 0, ng = 1;  // subjects, between cells
  double nu = 0;              // error degrees of freedom of a per-subject quantity

  explicit BetweenCells(const RmAnovaResult& anova)
      : a(anova),
        n(anova.subjects.size()),
        ng(anova.group_sizes.empty() ? 1 : anova.group_sizes.size()),
        nu(anova.error_df > 0 ? anova.error_df : static_cast<double>(n) - 1) {}
  std::size_t GroupOf(std::size_t s) const {
    return a.subject_group.empty() ? std::size_t{0} : static_cast<std::size_t>(a.subject_group[s]);
  }
  double SizeOf(std::size_t g) const {
    return a.group_sizes.empty() ? static_cast<double>(n) : static_cast<double>(a.group_sizes[g]);
  }
  // Unweighted mean over the between cells of a per-subject quantity v (emmeans averages the
  // between cells equally), and the residual variance of v around its cell means.
  double Unweighted(const std::vector<double>& v, double* resid_var) const {
    std::vector<double> sum(ng, 0.0);
    for (std::size_t s = 0; s < n; ++s) sum[GroupOf(s)] += v[s];
    double mean = 0;
    for (std::size_t g = 0; g < ng; ++g) mean += sum[g] / SizeOf(g);
    if (resid_var) {
      double ss = 0;
      for (std::size_t s = 0; s < n; ++s)
        ss += std::pow(v[s] - sum[GroupOf(s)] / SizeOf(GroupOf(s)), 2);
      *resid_var = ss / nu;
    }
    return mean / static_cast<double>(ng);
  }
  // (1/G^2) sum_g 1/n_g: the variance factor of an unweighted mean over the between cells.
  double InvN() const {
    double inv_n = 0;
    for (std::size_t g = 0; g < ng; ++g) inv_n += 1.0 / SizeOf(g);
    inv_n /= static_cast<double>(ng * ng);
    return inv_n;
  }
};

// Between factor bf: each subject's mean over all cells; level means average the between cells
// of the level equally; per-cell error from the subjects around their cell means.
void PairsBetween(const BetweenCells& b, std::size_t bf, double conf, TukeyResult& r) {
  const RmAnovaResult& a = b.a;
  const std::size_t n = b.n, ng = b.ng, nc = a.cells.empty() ? 0 : a.cells[0].size();
  r.method = "between-subjects (mixed ANOVA)";
  const auto& levels = a.between_levels[bf];
  r.k = static_cast<int>(levels.size());
  std::vector<double> m(n, 0.0);
  for (std::size_t s = 0; s < n; ++s) {
    for (double v : a.cells[s]) m[s] += v;
    m[s] /= static_cast<double>(nc);
  }
  std::vector<double> mu(ng, 0.0);
  for (std::size_t s = 0; s < n; ++s) mu[b.GroupOf(s)] += m[s];
  double ss = 0;
  for (std::size_t g = 0; g < ng; ++g) mu[g] /= b.SizeOf(g);
  for (std::size_t s = 0; s < n; ++s) ss += std::pow(m[s] - mu[b.GroupOf(s)], 2);
  r.mse = ss / b.nu;
  r.df = b.nu;
  std::size_t stride = 1;
  for (std::size_t g = bf + 1; g < a.between.size(); ++g) stride *= a.between_levels[g].size();
  const std::size_t kf = levels.size();
  auto level_of = [&](std::size_t g) { return (g / stride) % kf; };
  // ng is the product of the between factors' level counts, kf one of them: exact division.
  const double per_level = static_cast<double>(ng / kf);  // NOLINT(bugprone-integer-division)
  AddPairs(r, levels, conf, [&](std::size_t i, std::size_t j, double* diff, double* se) {
    double est = 0, var = 0;
    for (std::size_t g = 0; g < ng; ++g) {
      const double c = level_of(g) == j ? 1 / per_level : level_of(g) == i ? -1 / per_level : 0.0;
      est += c * mu[g];
      var += c * c / b.SizeOf(g);
    }
    *diff = est;
    *se = std::sqrt(r.mse * var);
  });
}

// Within factor f: the subjects' marginal means of each level (averaged over the other
// factors' cells), pairs from the ANOVA's error term (univariate) or each difference's own
// variance (multivariate).
void PairsWithin(const BetweenCells& b, std::size_t f, bool multivariate, double conf,
                 TukeyResult& r) {
  const RmAnovaResult& a = b.a;
  const std::size_t n = b.n, nc = a.cells.empty() ? 0 : a.cells[0].size();
  const double inv_n = b.InvN();
  r.method = multivariate ? "multivariate" : "univariate";
  const auto& levels = a.levels[f];
  r.k = static_cast<int>(levels.size());
  // Subject marginal means of each level (averaged over the other factors' cells).
  std::size_t stride = 1;
  for (std::size_t g = f + 1; g < a.factors.size(); ++g) stride *= a.levels[g].size();
  const std::size_t kf = levels.size();
  std::vector<std::vector<double>> m(n, std::vector<double>(kf, 0.0));
  for (std::size_t s = 0; s < n; ++s) {
    for (std::size_t c = 0; c < nc; ++c) m[s][(c / stride) % kf] += a.cells[s][c];
    // nc is the product of the factors' level counts, kf one of them: exact division.
    for (auto& v : m[s]) v /= static_cast<double>(nc / kf);  // NOLINT(bugprone-integer-division)
  }
  const AnovaEffect* main = nullptr;
  for (const auto& e : a.effects)
    if (e.effect == r.factor) main = &e;
  r.mse = main->MSE;
  r.df = multivariate ? b.nu : main->df2;
  // nc / kf: exact, as above.
  const double cells_per_level = static_cast<double>(nc / kf);  // NOLINT(bugprone-integer-division)
  AddPairs(r, levels, conf, [&](std::size_t i, std::size_t j, double* diff, double* se) {
    std::vector<double> d(n);
    for (std::size_t s = 0; s < n; ++s) d[s] = m[s][j] - m[s][i];
    double var = 0;
    *diff = b.Unweighted(d, &var);
    *se = multivariate ? std::sqrt(var * inv_n) : std::sqrt(2 * r.mse / cells_per_level * inv_n);
  });
}

}  // namespace

TukeyResult TukeyWithin(const RmAnovaResult& a, const std::string& factor, bool multivariate,
                        double conf) {
  TukeyResult r;
  r.factor = factor;
  const BetweenCells cells(a);
  std::size_t bf = 0;
  while (bf < a.between.size() && a.between[bf] != factor) ++bf;
  if (bf < a.between.size()) {
    PairsBetween(cells, bf, conf, r);
    return r;
  }
  std::size_t f = 0;
  while (f < a.factors.size() && a.factors[f] != factor) ++f;
  if (f == a.factors.size())
    throw InputError("<command line>", 0, "factor",
                     "'" + factor + "' is not a factor of this ANOVA");
  PairsWithin(cells, f, multivariate, conf, r);
  return r;
}

}  // namespace hapticlab::stats
