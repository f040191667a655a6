#include "hapticlab/stats/tukey.hpp"

#include <cmath>
#include <map>
#include <numbers>

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
  const TukeyFamily fam(r.k, r.df);
  const double q_crit = fam.Quantile(conf);
  for (std::size_t i = 0; i < levels.size(); ++i)
    for (std::size_t j = i + 1; j < levels.size(); ++j) {
      const auto& si = sum[levels[i]];
      const auto& sj = sum[levels[j]];
      TukeyPair p;
      p.a = levels[j];
      p.b = levels[i];
      p.diff = sj.first / sj.second - si.first / si.second;
      p.se = std::sqrt(r.mse * (1.0 / si.second + 1.0 / sj.second));
      p.df = r.df;
      Fill(p, fam, q_crit);
      r.pairs.push_back(p);
    }
  return r;
}

TukeyResult TukeyWithin(const RmAnovaResult& a, const std::string& factor, bool multivariate, double conf) {
  TukeyResult r;
  r.method = multivariate ? "multivariate" : "univariate";
  r.factor = factor;
  std::size_t f = 0;
  while (f < a.factors.size() && a.factors[f] != factor) ++f;
  if (f == a.factors.size()) throw InputError("", 0, factor, "not a within factor of this ANOVA");
  const auto& levels = a.levels[f];
  r.k = static_cast<int>(levels.size());
  // Subject marginal means of each level (averaged over the other factors' cells).
  const std::size_t n = a.subjects.size(), nc = a.cells.empty() ? 0 : a.cells[0].size();
  std::size_t stride = 1;
  for (std::size_t g = f + 1; g < a.factors.size(); ++g) stride *= a.levels[g].size();
  const std::size_t kf = levels.size();
  std::vector<std::vector<double>> m(n, std::vector<double>(kf, 0.0));
  for (std::size_t s = 0; s < n; ++s) {
    for (std::size_t c = 0; c < nc; ++c) m[s][(c / stride) % kf] += a.cells[s][c];
    for (auto& v : m[s]) v /= static_cast<double>(nc / kf);
  }
  const AnovaEffect* main = nullptr;
  for (const auto& e : a.effects)
    if (e.effect == factor) main = &e;
  r.mse = main->MSE;
  r.df = multivariate ? static_cast<double>(n) - 1 : main->df2;
  const double cells_per_level = static_cast<double>(nc / kf);
  const TukeyFamily fam(r.k, r.df);
  const double q_crit = fam.Quantile(conf);
  for (std::size_t i = 0; i < kf; ++i)
    for (std::size_t j = i + 1; j < kf; ++j) {
      TukeyPair p;
      p.a = levels[j];
      p.b = levels[i];
      double mean = 0;
      for (std::size_t s = 0; s < n; ++s) mean += m[s][j] - m[s][i];
      mean /= static_cast<double>(n);
      p.diff = mean;
      if (multivariate) {
        double ss = 0;
        for (std::size_t s = 0; s < n; ++s) ss += std::pow(m[s][j] - m[s][i] - mean, 2);
        p.se = std::sqrt(ss / (static_cast<double>(n) - 1) / static_cast<double>(n));
      } else {
        p.se = std::sqrt(2 * r.mse / (static_cast<double>(n) * cells_per_level));
      }
      p.df = r.df;
      Fill(p, fam, q_crit);
      r.pairs.push_back(p);
    }
  return r;
}

}  // namespace hapticlab::stats
