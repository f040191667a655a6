#pragma once
/// @file Vibration synthesis from an AR bank (dissertation ch. V.1.3; Culbertson et al.):
/// interpolate the AR model at the current (speed, normal force) in LSF form, then drive it
/// with Gaussian noise of the interpolated residual variance.

#include <array>
#include <cstdint>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/material.hpp"

namespace hapticlab::renderer {

/// An AR filter ready to run: what the force thread hands to the vibration thread.
struct ArFilter {
  std::array<double, kMaxArOrder> c{};  ///< AR coefficients c_1..c_order
  int order = 0;
  std::array<double, kMaxArOrder> b{};  ///< MA coefficients b_1..b_ma_order (ARMA only)
  int ma_order = 0;
  double gain = 1;      ///< excitation gain (dimensionless)
  double sigma = 0;     ///< residual standard deviation [m/s^2]
  bool active = false;  ///< false: out of contact or slower than the bank's minimum speed
  double speed_mps = 0, force_N = 0;  ///< the condition (for the neural model's inputs)
};

/// Weights of the bank's cells at one (speed, force) point: up to four cells (grid) or three
/// (triangle), weights >= 0 summing to 1.
struct CellWeights {
  std::array<int, 4> cell{};
  std::array<double, 4> weight{};
  int count = 0;
};

/// Computes interpolation weights and interpolated filters. All buffers are sized in the
/// constructor; Weights and Interpolate are noexcept and allocation-free.
class VibrationInterpolator {
 public:
  VibrationInterpolator() = default;
  explicit VibrationInterpolator(const VibrationBank& bank);

  /// Grid: bilinear over the four neighbours (the thesis's scheme), clamped at the edges.
  /// Triangulation: barycentric in the containing triangle; outside the hull, the triangle
  /// whose barycentric coordinates are least negative, with negatives clamped to zero.
  CellWeights Weights(double speed_mps, double force_N) const noexcept;

  /// Interpolated filter at (speed, force): LSFs and variance mixed with the weights, then
  /// converted back to AR coefficients. `active` follows the bank's minimum speed and
  /// `in_contact`. A speed or force above the bank's modelled range (max_speed_mps,
  /// max_force_N) saturates just inside it first.
  void Interpolate(double speed_mps, double force_N, bool in_contact, ArFilter* out) noexcept;

  const VibrationBank& bank() const { return bank_; }

 private:
  VibrationBank bank_;
  std::vector<double> lsf_, work_, coeff_, ma_lsf_, ma_coeff_;
};

/// Deterministic Gaussian noise (hapticlab::Rng: xoshiro256** with Box-Muller): the same
/// sequence on every platform for a seed.
using GaussianNoise = Rng;

/// Runs an AR(MA) filter on noise: a[k] = sum c_i a[k-i] + gain (x[k] + sum b_j x[k-j]),
/// x = sigma * N(0, 1). When the filter becomes
/// inactive the output is zero and the history is cleared. Step is noexcept and
/// allocation-free.
class ArSynth {
 public:
  explicit ArSynth(std::uint64_t seed = 1) : noise_(seed) {}
  void Reset() noexcept;
  /// Next sample with Gaussian excitation of standard deviation f.sigma.
  double Step(const ArFilter& f) noexcept { return StepWith(f, f.sigma * noise_.Normal()); }
  /// Next sample with a given excitation x[k] (impulse responses, tests, replay).
  double StepWith(const ArFilter& f, double x) noexcept;

 private:
  GaussianNoise noise_;
  std::array<double, kMaxArOrder> hist_{};  // ring buffer of past outputs
  std::array<double, kMaxArOrder> exc_{};   // ring buffer of past excitations
  int head_ = 0;
  bool running_ = false;
};

}  // namespace hapticlab::renderer
