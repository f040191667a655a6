#pragma once
/// @file Autoregressive (AR/LPC) filter utilities: line spectral frequencies, stability,
/// spectra.
///
/// Convention used throughout HapticLab: an AR(p) process is
///   a[k] = sum_{i=1..p} c_i a[k-i] + e[k],   e ~ N(0, sigma^2),
/// with `c` the "AR coefficients" (dimensionless) and the prediction-error polynomial
///   A(z) = 1 - sum_i c_i z^-i.
/// Files that store A(z) itself ([1, a_1, ..., a_p], MATLAB's `lpc` convention, as the Penn
/// Haptic Texture Toolkit does) convert with c_i = -a_i.
///
/// Line spectral frequencies (LSFs) are the p angles in (0, pi) [rad/sample] where
/// P(z) = A(z) + z^-(p+1) A(1/z) and Q(z) = A(z) - z^-(p+1) A(1/z) vanish on the unit circle.
/// A(z) is minimum phase (the synthesis filter 1/A is stable) exactly when the LSFs are
/// strictly increasing and alternate between P and Q [Soong & Juang 1984,
/// doi:10.1109/ICASSP.1984.1172448]; a convex combination of sorted LSF vectors is sorted,
/// so interpolating in LSF form never yields an unstable filter.

#include <complex>
#include <span>
#include <vector>

namespace hapticlab::renderer {

/// Highest AR order the real-time synthesis supports.
inline constexpr int kMaxArOrder = 64;

/// LSFs [rad/sample], ascending, of the AR coefficients `c` (size p).
/// @throws PreconditionError when A(z) is not minimum phase (no valid LSFs exist; check
/// IsStableAr first).
std::vector<double> ArToLsf(std::span<const double> c);

/// AR coefficients `c` (size p) from ascending LSFs [rad/sample] in (0, pi).
/// Allocation-free: writes `lsf.size()` coefficients into `c_out`, using `work` (size at
/// least 4 * (p + 2)) as scratch.
void LsfToAr(std::span<const double> lsf, std::span<double> c_out, std::span<double> work) noexcept;

/// Convenience overload that allocates.
std::vector<double> LsfToAr(std::span<const double> lsf);

/// True when all roots of A(z) lie strictly inside the unit circle (Schur-Cohn / step-down
/// recursion on the reflection coefficients).
bool IsStableAr(std::span<const double> c);

/// One-sided power spectral density of the AR process [units^2/Hz] at frequency f_hz:
/// S(f) = 2 sigma^2 / (fs |A(e^{j 2 pi f/fs})|^2).
double ArPsd(std::span<const double> c, double variance, double fs_hz, double f_hz);

}  // namespace hapticlab::renderer
