#pragma once
/// @file Workbench ground-truth simulator: synthetic measurements with known parameters.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "hapticlab/modeling/workbench_predict.hpp"

namespace hapticlab::modeling::wb {

// ---------------------------------------------------------------------------------------------
// Ground-truth simulator (tests, docs, `hapticlab measurement simulate`): an independent
// implementation of the effects' physics (Euler-integrated bristles at 20 substeps per sample,
// an AR(2) resonance at the surface's spatial frequency for vibration) driven by human-like
// strokes; noise on forces, positions, velocities and acceleration.
struct TruthParams {
  std::vector<std::string> effects;  ///< which effects the truth has (BaselineEffects() by default)
  double K1mm_N = 1.5, n = 1.3, B1mm_Ns_per_m = 20;  ///< n with hc-exponent, B with hc-damping
  double base_K_N_per_m = 6000, layer_m = 0.6e-3;    ///< base-layer
  double mu_k = 0.3, kappa_N_per_m = 3000, mu_b_Ns_per_m = 0.5;
  double stribeck_dmu = 0.25, stribeck_vs_mps = 0.004;
  std::array<double, 4> aniso{0.0, 0.0, 0.25, 0.0};  ///< a1, b1, a2, b2 of 1 + a1 cos φ + ...
  double load_alpha = 0.7;                           ///< f_C ∝ f_n^alpha
  double tile_amp = 0.25;                            ///< µ varies by about ± this over the area
  double vib_sigma = 2.0, vib_speed_exp = 1.0, vib_force_exp = 0.8, vib_dir_amp = 0.8;
  double wavelength_m = 0.4e-3;  ///< spatial period of the micro-geometry
  /// Out of the catalogue (tests of `diagnose`'s unexplained report): mu_k drifts linearly by
  /// this fraction over the recording (mu_k (1 + mu_drift (t / duration - 1/2))), and the
  /// stiffness varies over the surface (K1mm (1 + K_position_amp x / (area / 2))).
  double mu_drift = 0, K_position_amp = 0;
  double force_noise_N = 0.005, pos_noise_m = 0.2e-6, vel_noise_mps = 0.2e-3, acc_noise = 0.05;
  double duration_s = 30, rate_hz = 2000;
  double area_m = 0.04;  ///< strokes stay in a square of this side
  std::uint64_t seed = 1;
  bool Has(std::string_view e) const;
};
struct SimulatedMeasurement {
  TruthParams truth;
  Measurement m;
  std::vector<double> fn_clean, ftx_clean, fty_clean;  ///< noise-free forces per row
  /// Per row, the vibration process: excitation variance, AR(2) a1, a2, sensor noise variance
  /// (the expected periodogram follows analytically).
  std::vector<std::array<double, 4>> acc_state;
};
SimulatedMeasurement Simulate(const TruthParams& t);
/// The truth expressed as a workbench model (force channels; the vibration truth has another
/// form): the truth's parameters, the position field re-expanded on the replay's area.
Model TruthModel(const SimulatedMeasurement& sim, const Replay& r);
/// Noise floor on a split: the truth replayed through the measured (noisy) kinematics for the
/// force channels — no model can beat it on average — and, for vibration, E_s of the measured
/// band powers against their analytic expectation.
Errors NoiseFloor(const SimulatedMeasurement& sim, const Replay& r, Split split);
/// The noise-free forces against the measurement (below NoiseFloor by the input noise).
Errors CleanSignalErrors(const SimulatedMeasurement& sim, const Replay& r, Split split);

}  // namespace hapticlab::modeling::wb
