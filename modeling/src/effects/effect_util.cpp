#include "effect_util.hpp"

namespace hapticlab::modeling::wb::detail {

int Bins::ArgMax(int min_n) const {
  int best = -1;
  for (std::size_t j = 0; j < mean.size(); ++j)
    if (n[j] >= min_n && (best < 0 || mean[j] > mean[best])) best = static_cast<int>(j);
  return best;
}
int Bins::ArgMin(int min_n) const {
  int best = -1;
  for (std::size_t j = 0; j < mean.size(); ++j)
    if (n[j] >= min_n && (best < 0 || mean[j] < mean[best])) best = static_cast<int>(j);
  return best;
}
int Bins::First(int min_n) const {
  for (std::size_t j = 0; j < mean.size(); ++j)
    if (n[j] >= min_n) return static_cast<int>(j);
  return -1;
}
int Bins::Last(int min_n) const {
  for (std::size_t j = mean.size(); j-- > 0;)
    if (n[j] >= min_n) return static_cast<int>(j);
  return -1;
}

double MeanBandResidualDb(const Residuals& res, std::size_t w) {
  double s = 0;
  for (const double x : res.log_band[w]) s += x;
  return res.log_band[w].empty()
             ? 0
             : 10.0 / std::log(10.0) * s / static_cast<double>(res.log_band[w].size());
}

}  // namespace hapticlab::modeling::wb::detail

namespace hapticlab::modeling::wb::detail {

void Hats(const double* t, int K, double u, double* out) {
  for (int k = 0; k < K; ++k) out[k] = 0;
  if (u <= t[0]) {
    out[0] = 1;
    return;
  }
  if (u >= t[K - 1]) {
    out[K - 1] = 1;
    return;
  }
  for (int k = 0; k + 1 < K; ++k) {
    if (u <= t[k + 1]) {
      const double w = (u - t[k]) / std::max(t[k + 1] - t[k], 1e-12);
      out[k] = 1 - w;
      out[k + 1] = w;
      return;
    }
  }
}

std::vector<double> LogQuantileKnots(const Replay& r, int K, bool speed) {
  std::vector<double> v;
  for (const auto& w : r.windows)
    v.push_back(std::log(speed ? w.speed_mps : std::max(w.force_N, 1e-3)));
  std::vector<double> knots;
  if (v.empty()) {
    for (int k = 0; k < K; ++k) knots.push_back(speed ? std::log(0.01) + k : k - 1.0);
    return knots;
  }
  std::sort(v.begin(), v.end());
  for (int k = 0; k < K; ++k) {
    double q =
        v[std::min(v.size() - 1, static_cast<std::size_t>(static_cast<double>(k) / (K - 1) *
                                                          static_cast<double>(v.size() - 1)))];
    if (!knots.empty() && q <= knots.back() + 1e-3) q = knots.back() + 1e-3;
    knots.push_back(q);
  }
  return knots;
}

}  // namespace hapticlab::modeling::wb::detail
