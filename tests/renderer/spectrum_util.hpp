#pragma once
// Test-only spectral helpers: Welch PSD by a direct DFT and the relative spectral RMS error.

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

namespace hapticlab::test {

// In-place radix-2 FFT (size a power of two).
inline void Fft(std::vector<std::complex<double>>& a) {
  const std::size_t n = a.size();
  for (std::size_t i = 1, j = 0; i < n; ++i) {
    std::size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(a[i], a[j]);
  }
  for (std::size_t len = 2; len <= n; len <<= 1) {
    const std::complex<double> w =
        std::polar(1.0, -2 * std::numbers::pi / static_cast<double>(len));
    for (std::size_t i = 0; i < n; i += len) {
      std::complex<double> wk(1.0, 0.0);
      for (std::size_t k = 0; k < len / 2; ++k, wk *= w) {
        const auto u = a[i + k], v = a[i + k + len / 2] * wk;
        a[i + k] = u + v;
        a[i + k + len / 2] = u - v;
      }
    }
  }
}

// One-sided Welch PSD [units^2/Hz] with a Hann window, 50 % overlap, bins 0..n/2 (bin k at
// k fs / n), by FFT; n a power of two.
inline std::vector<double> WelchPsdFft(const std::vector<double>& x, double fs, int n) {
  const auto N = static_cast<std::size_t>(n);
  std::vector<double> w(N), psd(N / 2 + 1, 0.0);
  double wss = 0;
  for (std::size_t i = 0; i < N; ++i) {
    w[i] = 0.5 -
           0.5 * std::cos(2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(N));
    wss += w[i] * w[i];
  }
  std::vector<std::complex<double>> buf(N);
  int segments = 0;
  for (std::size_t start = 0; start + N <= x.size(); start += N / 2, ++segments) {
    for (std::size_t i = 0; i < N; ++i) buf[i] = w[i] * x[start + i];
    Fft(buf);
    for (std::size_t k = 0; k <= N / 2; ++k)
      psd[k] += ((k == 0 || k == N / 2) ? 1.0 : 2.0) * std::norm(buf[k]) / (fs * wss);
  }
  for (auto& v : psd) v /= segments;
  return psd;
}

// One-sided Welch PSD [units^2/Hz] with a Hann window, 50 % overlap, bins 0..n/2.
inline std::vector<double> WelchPsd(const std::vector<double>& x, double fs, int n) {
  const auto N = static_cast<std::size_t>(n);
  std::vector<double> w(N), psd(N / 2 + 1, 0.0);
  double wss = 0;
  for (std::size_t i = 0; i < N; ++i) {
    w[i] = 0.5 -
           0.5 * std::cos(2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(N));
    wss += w[i] * w[i];
  }
  int segments = 0;
  for (std::size_t start = 0; start + N <= x.size(); start += N / 2, ++segments) {
    for (std::size_t k = 0; k <= N / 2; ++k) {
      double re = 0, im = 0;
      for (std::size_t i = 0; i < N; ++i) {
        const double ang =
            -2 * std::numbers::pi * static_cast<double>(k * i) / static_cast<double>(N);
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
