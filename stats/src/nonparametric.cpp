#include "hapticlab/stats/nonparametric.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/distributions.hpp"

namespace hapticlab::stats {

KruskalResult KruskalWallis(const LongTable& data, const std::string& factor) {
  KruskalResult r;
  r.factor = factor;
  r.groups = data.Levels(factor);
  const auto c = data.Key(factor);
  const int k = static_cast<int>(r.groups.size());
  if (k < 2) throw InputError(data.source, 0, factor, "Kruskal-Wallis needs at least 2 groups");
  const std::size_t N = data.rows();
  r.N = static_cast<int>(N);
  std::vector<double> v(N);
  for (std::size_t i = 0; i < N; ++i) v[i] = std::round(data.y[i] * 1e9) / 1e9;
  // Mid-ranks.
  std::vector<std::size_t> order(N);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
  std::vector<double> rank(N);
  double ties = 0;  // sum of t^3 - t
  for (std::size_t i = 0; i < N;) {
    std::size_t j = i;
    while (j + 1 < N && v[order[j + 1]] == v[order[i]]) ++j;
    const double mid = 0.5 * static_cast<double>(i + j) + 1.0;
    for (std::size_t t = i; t <= j; ++t) rank[order[t]] = mid;
    const double t = static_cast<double>(j - i + 1);
    ties += t * t * t - t;
    i = j + 1;
  }
  std::map<std::string, std::pair<double, int>> rs;
  for (std::size_t i = 0; i < N; ++i) {
    auto& g = rs[data.keys[c][i]];
    g.first += rank[i];
    g.second += 1;
  }
  const double n = static_cast<double>(N);
  double sum = 0;
  for (const auto& [g, s] : rs) sum += s.first * s.first / s.second;
  r.H_uncorrected = 12.0 / (n * (n + 1)) * sum - 3 * (n + 1);
  r.tie_correction = 1 - ties / (n * n * n - n);
  if (!(r.tie_correction > 0)) throw InputError(data.source, 0, data.y_name, "all values are tied");
  r.H = r.H_uncorrected / r.tie_correction;
  r.df = k - 1;
  r.p = PchisqUpper(r.H, r.df);
  // Dunn (1964) with the tie-corrected variance; Bonferroni over every pair.
  const double var = n * (n + 1) / 12.0 - ties / (12.0 * (n - 1));
  const double m = k * (k - 1) / 2.0;
  for (int i = 0; i < k; ++i)
    for (int j = i + 1; j < k; ++j) {
      const auto& gi = rs[r.groups[static_cast<std::size_t>(i)]];
      const auto& gj = rs[r.groups[static_cast<std::size_t>(j)]];
      DunnPair d;
      d.a = r.groups[static_cast<std::size_t>(i)];
      d.b = r.groups[static_cast<std::size_t>(j)];
      d.n_a = gi.second;
      d.n_b = gj.second;
      d.z = (gj.first / gj.second - gi.first / gi.second) /
            std::sqrt(var * (1.0 / gi.second + 1.0 / gj.second));
      d.p = PnormTwoSided(d.z);
      d.p_adj = std::min(1.0, d.p * m);
      r.dunn.push_back(d);
    }
  return r;
}

std::vector<LimitGroup> GroupAgainstLimits(const LongTable& data, const std::string& factor,
                                           const std::string& upper, const std::string& lower,
                                           double alpha) {
  const auto kw = KruskalWallis(data, factor);
  auto padj = [&](const std::string& x, const std::string& y) {
    for (const auto& d : kw.dunn)
      if ((d.a == x && d.b == y) || (d.a == y && d.b == x)) return d.p_adj;
    throw InputError(data.source, 0, factor, "group '" + y + "' not found");
  };
  std::vector<LimitGroup> out;
  for (const auto& g : kw.groups) {
    if (g == upper || g == lower) continue;
    LimitGroup l;
    l.material = g;
    l.p_adj_vs_upper = padj(g, upper);
    l.p_adj_vs_lower = padj(g, lower);
    const bool du = l.p_adj_vs_upper < alpha, dl = l.p_adj_vs_lower < alpha;
    l.letter = dl && !du ? "A" : du && !dl ? "B" : !du && !dl ? "C" : "D";
    out.push_back(l);
  }
  return out;
}

}  // namespace hapticlab::stats
