#pragma once
// Test-only spectral helpers: Welch PSD by a direct DFT and the relative spectral RMS error.

#include <cmath>
#include <numbers>
#include <vector>

namespace hapticlab::test {

// One-sided Welch PSD [units^2/Hz] with a Hann window, 50 % overlap, bins 0..n/2.
inline std::vector<double> WelchPsd(const std::vector<double>& x, double fs, int n) {
  const auto N = static_cast<std::size_t>(n);
  std::vector<double> w(N), psd(N / 2 + 1, 0.0);
  double wss = 0;
  for (std::size_t i = 0; i < N; ++i) {
    w[i] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(N));
    wss += w[i] * w[i];
  }
  int segments = 0;
  for (std::size_t start = 0; start + N <= x.size(); start += N / 2, ++segments) {
    for (std::size_t k = 0; k <= N / 2; ++k) {
      double re = 0, im = 0;
      for (std::size_t i = 0; i < N; ++i) {
        const double ang = -2 * std::numbers::pi * static_cast<double>(k * i) / static_cast<double>(N);
        re += w[i] * x[start + i] * std::cos(ang);
        im += w[i] * x[start + i] * std::sin(ang);
      }
      const double scale = (k == 0 || k == N / 2) ? 1.0 : 2.0;
      psd[k] += scale * (re * re + im * im) / (fs * wss);
    }
  }
  for (auto& v : psd) v /= segments;
  return psd;
}

// E_s (dissertation eq. 3.1) on magnitude spectra: RMS(|A| - |B|) / RMS(|B|), with the
// magnitudes taken as sqrt(PSD). Bins 1..n-2 (DC and Nyquist excluded).
inline double RelativeSpectralRms(const std::vector<double>& psd, const std::vector<double>& ref) {
  double num = 0, den = 0;
  for (std::size_t k = 1; k + 1 < psd.size(); ++k) {
    const double a = std::sqrt(psd[k]), b = std::sqrt(ref[k]);
    num += (a - b) * (a - b);
    den += b * b;
  }
  return std::sqrt(num / den);
}

}  // namespace hapticlab::test
