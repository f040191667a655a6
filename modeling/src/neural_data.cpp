// The neural models' training data: the recordings' grid, the ideal band split and the
// validation score (neural_internal.hpp).

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <mutex>

#include "hapticlab/modeling/neural.hpp"
#include "neural_internal.hpp"

namespace hapticlab::modeling::neural_internal {

bool Near(double a, double b) { return std::abs(a - b) <= 1e-6 * std::max(1.0, std::abs(b)); }

std::vector<double> Unique(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  std::vector<double> u;
  for (const double x : v)
    if (u.empty() || !Near(x, u.back())) u.push_back(x);
  return u;
}

int Index(const std::vector<double>& g, double x) {
  for (std::size_t i = 0; i < g.size(); ++i)
    if (Near(x, g[i])) return static_cast<int>(i);
  return -1;
}

std::vector<double> BandSplit(const std::vector<double>& x, double fs, double lo, double hi) {
  const int n = static_cast<int>(x.size());
  if (n < 2) return x;
  std::vector<double> in(x), out(x.size());
  std::vector<fftw_complex> spec(static_cast<std::size_t>(n / 2 + 1));
  static std::mutex plan_mutex;  // FFTW's planner is not thread-safe
  fftw_plan fwd, inv;
  {
    std::lock_guard<std::mutex> lock(plan_mutex);
    fwd = fftw_plan_dft_r2c_1d(n, in.data(), spec.data(), FFTW_ESTIMATE);
    inv = fftw_plan_dft_c2r_1d(n, spec.data(), out.data(), FFTW_ESTIMATE);
  }
  fftw_execute(fwd);
  for (int k = 0; k <= n / 2; ++k) {
    const double f = k * fs / n;
    if (f < lo || f >= hi)
      spec[static_cast<std::size_t>(k)][0] = spec[static_cast<std::size_t>(k)][1] = 0;
  }
  fftw_execute(inv);
  {
    std::lock_guard<std::mutex> lock(plan_mutex);
    fftw_destroy_plan(fwd);
    fftw_destroy_plan(inv);
  }
  for (auto& v : out) v /= n;
  return out;
}

double ValidationEs(const renderer::NeuralModel& m, const std::vector<renderer::NeuralBand>& bands,
                    const std::vector<Recording>& recs, const std::vector<std::vector<double>>& pre,
                    double validation_fraction, std::uint64_t seed) {
  renderer::NeuralModel cand = m;
  cand.bands = bands;
  double sum = 0;
  int count = 0;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const auto nval = static_cast<std::size_t>(
        std::floor(validation_fraction * static_cast<double>(pre[i].size())));
    if (nval < 2 * kValidationSegment) continue;
    const std::vector<double> held(pre[i].end() - static_cast<std::ptrdiff_t>(nval), pre[i].end());
    const auto synth = SynthesizeNeural(cand, recs[i].speed_mps, recs[i].force_N,
                                        16 * kValidationSegment, seed + i);
    sum += SpectralError(held, synth, kValidationSegment);
    ++count;
  }
  return count > 0 ? sum / count : 0.0;
}

}  // namespace hapticlab::modeling::neural_internal
