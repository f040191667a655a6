#include "hapticlab/stats/within_ci.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/distributions.hpp"

namespace hapticlab::stats {

std::vector<WithinCi> WithinSubjectCi(const LongTable& data, const std::string& subject,
                                      const std::vector<std::string>& factors, double level) {
  if (factors.empty())
    throw InputError(data.source, 0, subject, "within-subject CIs need at least one factor");
  std::vector<std::string> by{subject};
  by.insert(by.end(), factors.begin(), factors.end());
  const LongTable cells = data.Average(by);
  // The full crossing of the factors' levels, last factor fastest.
  std::vector<std::vector<std::string>> crossing{{}};
  for (const auto& f : factors) {
    std::vector<std::vector<std::string>> next;
    for (const auto& c : crossing)
      for (const auto& l : data.Levels(f)) {
        next.push_back(c);
        next.back().push_back(l);
      }
    crossing = std::move(next);
  }
  std::map<std::vector<std::string>, std::size_t> index;
  for (std::size_t i = 0; i < crossing.size(); ++i) index[crossing[i]] = i;
  const std::size_t J = crossing.size();
  std::map<std::string, std::vector<double>> per;  // subject -> cell means (NaN: missing)
  for (std::size_t r = 0; r < cells.rows(); ++r) {
    std::vector<std::string> key;
    for (std::size_t f = 1; f < by.size(); ++f) key.push_back(cells.keys[f][r]);
    auto& v = per[cells.keys[0][r]];
    v.resize(J, std::numeric_limits<double>::quiet_NaN());
    v[index.at(key)] = cells.y[r];
  }
  // Complete subjects, normalised: y - subject mean + grand mean.
  std::vector<std::vector<double>> y;
  for (const auto& [s, v] : per) {
    bool complete = true;
    for (double x : v) complete = complete && !std::isnan(x);
    if (complete) y.push_back(v);
  }
  const std::size_t n = y.size();
  double grand = 0;
  std::vector<double> subject_mean(n, 0.0);
  for (std::size_t s = 0; s < n; ++s) {
    for (double x : y[s]) subject_mean[s] += x;
    subject_mean[s] /= static_cast<double>(J);
    grand += subject_mean[s];
  }
  grand /= static_cast<double>(std::max<std::size_t>(n, 1));
  const double morey = J > 1 ? std::sqrt(static_cast<double>(J) / static_cast<double>(J - 1)) : 1;
  const double t = n > 1 ? Qt(1 - (1 - level) / 2, static_cast<double>(n - 1)) : NAN;
  std::vector<WithinCi> out;
  for (std::size_t c = 0; c < J; ++c) {
    WithinCi w{.cell = crossing[c], .n = static_cast<int>(n)};
    double mean = 0;
    for (std::size_t s = 0; s < n; ++s) mean += y[s][c] - subject_mean[s] + grand;
    mean /= static_cast<double>(std::max<std::size_t>(n, 1));
    double ss = 0;
    for (std::size_t s = 0; s < n; ++s) {
      const double d = y[s][c] - subject_mean[s] + grand - mean;
      ss += d * d;
    }
    w.mean = n ? mean : std::numeric_limits<double>::quiet_NaN();
    w.half_width = n > 1 ? t * std::sqrt(ss / static_cast<double>(n - 1)) /
                               std::sqrt(static_cast<double>(n)) * morey
                         : std::numeric_limits<double>::quiet_NaN();
    out.push_back(std::move(w));
  }
  return out;
}

}  // namespace hapticlab::stats
