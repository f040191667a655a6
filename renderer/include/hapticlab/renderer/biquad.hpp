#pragma once
/// @file Second-order IIR sections (biquads): Butterworth low- and high-pass, designed once
/// by the bilinear transform with frequency pre-warping, run allocation-free.

#include <cmath>
#include <numbers>

namespace hapticlab::renderer {

/// Normalized biquad coefficients (a0 = 1):
/// y[n] = b0 x[n] + b1 x[n-1] + b2 x[n-2] - a1 y[n-1] - a2 y[n-2].
struct BiquadCoeffs {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;

  /// Second-order Butterworth low-pass (Q = 1/sqrt(2)): gain 1 at DC, -3 dB at cutoff_hz.
  /// @pre 0 < cutoff_hz < sample_rate_hz / 2
  static BiquadCoeffs ButterworthLowPass(double cutoff_hz, double sample_rate_hz);
  /// Second-order Butterworth high-pass: gain 1 at Nyquist, -3 dB at cutoff_hz.
  static BiquadCoeffs ButterworthHighPass(double cutoff_hz, double sample_rate_hz);
  /// Pass-through.
  static BiquadCoeffs Identity() { return {}; }

  /// |H(e^{j 2 pi f / fs})|, for tests and reports.
  double Magnitude(double f_hz, double sample_rate_hz) const;
};

/// A biquad's state (transposed direct form II). Step is noexcept and allocation-free.
class Biquad {
 public:
  Biquad() = default;
  explicit Biquad(const BiquadCoeffs& c) : c_(c) {}
  void SetCoeffs(const BiquadCoeffs& c) { c_ = c; }
  void Reset() { s1_ = s2_ = 0; }
  double Step(double x) noexcept {
    const double y = c_.b0 * x + s1_;
    s1_ = c_.b1 * x - c_.a1 * y + s2_;
    s2_ = c_.b2 * x - c_.a2 * y;
    return y;
  }

 private:
  BiquadCoeffs c_;
  double s1_ = 0, s2_ = 0;
};

}  // namespace hapticlab::renderer
