#pragma once
// Helpers shared by the effect files: binned means of residuals for the evidence texts.

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::modeling::wb::detail {

using wb::kPreslidingSpeed_mps;
using wb::kSlidingSpeed_mps;

struct Bins {
  std::vector<double> lo, hi, mean;
  std::vector<int> n;
  /// Index of the populated bin (>= min_n samples) with the largest / smallest mean; -1 if none.
  int ArgMax(int min_n = 20) const;
  int ArgMin(int min_n = 20) const;
  /// First and last populated bins.
  int First(int min_n = 20) const;
  int Last(int min_n = 20) const;
};

/// Means of `value(i)` grouped by `key(i)` into [edges[k], edges[k+1]) for i with use(i).
template <class Value, class Key, class Use>
Bins BinMeans(std::size_t count, Value value, Key key, Use use, const std::vector<double>& edges) {
  Bins b;
  const std::size_t k = edges.size() - 1;
  b.lo.assign(edges.begin(), edges.end() - 1);
  b.hi.assign(edges.begin() + 1, edges.end());
  b.mean.assign(k, 0);
  b.n.assign(k, 0);
  for (std::size_t i = 0; i < count; ++i) {
    if (!use(i)) continue;
    const double x = key(i);
    for (std::size_t j = 0; j < k; ++j) {
      if (x >= edges[j] && x < edges[j + 1]) {
        b.mean[j] += value(i);
        ++b.n[j];
        break;
      }
    }
  }
  for (std::size_t j = 0; j < k; ++j)
    b.mean[j] = b.n[j] ? b.mean[j] / static_cast<double>(b.n[j]) : 0;
  return b;
}

/// Pearson correlation of value(i) and key(i) over i with use(i) (0 when degenerate).
template <class Value, class Key, class Use>
double Correlation(std::size_t count, Value value, Key key, Use use) {
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  int n = 0;
  for (std::size_t i = 0; i < count; ++i) {
    if (!use(i)) continue;
    const double x = key(i), y = value(i);
    sx += x, sy += y, sxx += x * x, syy += y * y, sxy += x * y;
    ++n;
  }
  if (n < 3) return 0;
  const double cxx = sxx - sx * sx / n, cyy = syy - sy * sy / n, cxy = sxy - sx * sy / n;
  return cxx > 0 && cyy > 0 ? cxy / std::sqrt(cxx * cyy) : 0;
}

/// What every catalogue entry states as data: its name (workbench_params.hpp), channel,
/// description paragraph and whether it modifies the Coulomb level (then it requires coulomb).
struct EffectInfo {
  std::string_view name;
  Channel channel = Channel::kFriction;
  bool modifies_coulomb = false;
  std::string_view description;
};

/// Base of the catalogue's effects: Effect's descriptive members from an EffectInfo.
class BasicEffect : public Effect {
 public:
  explicit BasicEffect(const EffectInfo& info) : info_(info) {}
  std::string_view name() const final { return info_.name; }
  Channel channel() const final { return info_.channel; }
  std::string_view description() const final { return info_.description; }
  std::vector<std::string_view> requires_effects() const final {
    if (info_.modifies_coulomb) return {effect::kCoulomb};
    return {};
  }

 private:
  EffectInfo info_;
};

/// A coefficient that modulates the friction coefficient, mu_k (1 + c ...): fitted within
/// +-0.9 (so mu stays positive), starting at 0 [1].
inline ParamSpec ModulationCoefficient(std::string name, std::string doc) {
  return {.name = std::move(name),
          .unit = "1",
          .init = 0,
          .lo = -0.9,
          .hi = 0.9,
          .scale = 0.1,
          .doc = std::move(doc)};
}

/// Sample i is in contact and sliding (speed >= kSlidingSpeed_mps).
inline bool Sliding(const Replay& r, std::size_t i) {
  return r.samples()[i].contact && r.samples()[i].speed_mps >= kSlidingSpeed_mps;
}
/// The friction-ratio residual of sample i (friction residual / f_n; 0 at loads <= 0.05 N).
inline double RatioResidual(const Replay& r, const Residuals& res, std::size_t i) {
  return r.samples()[i].fn_N > 0.05 ? res.friction_N[i] / r.samples()[i].fn_N : 0;
}
/// BinMeans over the force samples: value(i) by key(i) for the samples with use(i).
template <class Value, class Key, class Use>
Bins SampleBins(const Replay& r, Value value, Key key, Use use, const std::vector<double>& edges) {
  return BinMeans(r.samples().size(), value, key, use, edges);
}

/// Mean over bands of the log band-power residual of window w, in dB.
double MeanBandResidualDb(const Residuals& res, std::size_t w);

inline std::string Mn(double v) { return fmt::format("{:+.3f} N", v); }

}  // namespace hapticlab::modeling::wb::detail

namespace hapticlab::modeling::wb::detail {
/// Piecewise-linear "hat" basis on ascending knots (clamped outside): out[k] for k < K, sum 1.
void Hats(const double* knots, int K, double u, double* out);
/// K knots at quantiles of ln(key) over the vibration windows (distinct, ascending).
std::vector<double> LogQuantileKnots(const Replay& r, int K, bool speed);
}  // namespace hapticlab::modeling::wb::detail
