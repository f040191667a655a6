#include "hapticlab/stats/descriptive.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "hapticlab/core/status.hpp"
#include "hapticlab/stats/distributions.hpp"

namespace hapticlab::stats {
namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Mid-ranks of values rounded to 9 decimals (as the rank tests do: averaged scores that are
// equal in exact arithmetic must tie).
std::vector<double> MidRanks(const std::vector<double>& raw) {
  std::vector<double> x(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) x[i] = std::round(raw[i] * 1e9) / 1e9;
  std::vector<std::size_t> o(x.size());
  std::iota(o.begin(), o.end(), 0);
  std::sort(o.begin(), o.end(), [&](auto a, auto b) { return x[a] < x[b]; });
  std::vector<double> r(x.size());
  for (std::size_t i = 0; i < o.size();) {
    std::size_t j = i;
    while (j + 1 < o.size() && x[o[j + 1]] == x[o[i]]) ++j;
    for (std::size_t t = i; t <= j; ++t) r[o[t]] = 0.5 * static_cast<double>(i + j) + 1;
    i = j + 1;
  }
  return r;
}

}  // namespace

Descriptives Describe(const std::vector<double>& x) {
  Descriptives d;
  d.n = static_cast<int>(x.size());
  HL_REQUIRE(!x.empty(), "descriptives of an empty sample");
  d.mean = std::accumulate(x.begin(), x.end(), 0.0) / d.n;
  double ss = 0;
  for (double v : x) ss += (v - d.mean) * (v - d.mean);
  d.sd = d.n > 1 ? std::sqrt(ss / (d.n - 1)) : 0;
  d.se = d.sd / std::sqrt(static_cast<double>(d.n));
  d.median = Median(x);
  const double t = d.n > 1 ? Qt(0.975, d.n - 1) : 0;
  d.ci95_lo = d.mean - t * d.se;
  d.ci95_hi = d.mean + t * d.se;
  return d;
}

OutlierFence Outliers(const std::vector<double>& x, QuartileRule rule, double coef) {
  HL_REQUIRE(!x.empty(), "outliers of an empty sample");
  std::vector<double> s(x);
  std::sort(s.begin(), s.end());
  const double n = static_cast<double>(s.size());
  OutlierFence f;
  auto at = [&](double pos1) {  // 1-based position, may be fractional
    const auto lo = static_cast<std::size_t>(std::floor(pos1)) - 1,
               hi = static_cast<std::size_t>(std::ceil(pos1)) - 1;
    return 0.5 * (s[lo] + s[hi]);
  };
  if (rule == QuartileRule::kHinges) {
    // fivenum(): n4 = floor((n + 3) / 2) / 2; hinges at n4 and n + 1 - n4.
    const double n4 = std::floor((n + 3) / 2) / 2;
    f.q1 = at(n4);
    f.q3 = at(n + 1 - n4);
  } else {
    auto q7 = [&](double p) {
      const double h = (n - 1) * p;
      const auto lo = static_cast<std::size_t>(std::floor(h));
      const auto hi = std::min(lo + 1, s.size() - 1);
      return s[lo] + (h - std::floor(h)) * (s[hi] - s[lo]);
    };
    f.q1 = q7(0.25);
    f.q3 = q7(0.75);
  }
  const double iqr = f.q3 - f.q1;
  f.lower = f.q1 - coef * iqr;
  f.upper = f.q3 + coef * iqr;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (x[i] < f.lower || x[i] > f.upper) f.outliers.push_back(i);
  return f;
}

Correlation Pearson(const std::vector<double>& x, const std::vector<double>& y) {
  HL_REQUIRE(x.size() == y.size() && x.size() >= 3, "correlation needs paired samples of n >= 3");
  Correlation c;
  c.n = static_cast<int>(x.size());
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / c.n;
  const double my = std::accumulate(y.begin(), y.end(), 0.0) / c.n;
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  c.r = sxy / std::sqrt(sxx * syy);
  c.t = c.r * std::sqrt((c.n - 2) / (1 - c.r * c.r));
  c.p = PtTwoSided(c.t, c.n - 2);
  return c;
}

Correlation Spearman(const std::vector<double>& x, const std::vector<double>& y) {
  return Pearson(MidRanks(x), MidRanks(y));
}

}  // namespace hapticlab::stats
