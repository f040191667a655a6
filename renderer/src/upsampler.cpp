#include "hapticlab/renderer/upsampler.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "hapticlab/core/status.hpp"

namespace hapticlab::renderer {

PolyphaseUpsampler::PolyphaseUpsampler(int factor, int taps_per_phase)
    : factor_(factor), taps_(taps_per_phase) {
  HL_REQUIRE(factor >= 1 && taps_per_phase >= 1,
             "upsampler: factor and taps per phase must be >= 1");
  if (factor == 1) taps_ = 1;
  hist_.assign(2 * static_cast<std::size_t>(taps_), 0.0);
  h_.assign(static_cast<std::size_t>(taps_) * static_cast<std::size_t>(factor_), 0.0);
  const int len = taps_ * factor_;
  const double centre = 0.5 * (len - 1);
  for (int p = 0; p < factor_; ++p) {
    double sum = 0;
    for (int j = 0; j < taps_; ++j) {
      const int n = p + j * factor_;  // index within the full filter
      const double t = (n - centre) / factor_;
      const double sinc =
          std::abs(t) < 1e-12 ? 1.0 : std::sin(std::numbers::pi * t) / (std::numbers::pi * t);
      const double w = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * (n + 0.5) / len);
      const int tap = p * taps_ + j;
      sum += h_[static_cast<std::size_t>(tap)] = sinc * w;
    }
    for (int j = 0; j < taps_; ++j) {  // unit DC gain per phase
      const int tap = p * taps_ + j;
      h_[static_cast<std::size_t>(tap)] /= sum;
    }
  }
}

void PolyphaseUpsampler::Reset() noexcept {
  std::fill(hist_.begin(), hist_.end(), 0.0);
  head_ = 0;
}

}  // namespace hapticlab::renderer
