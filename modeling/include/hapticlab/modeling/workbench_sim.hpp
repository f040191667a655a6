#pragma once
/// @file Workbench ground-truth simulator: synthetic measurements with known parameters.

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "hapticlab/modeling/workbench_predict.hpp"

namespace hapticlab::modeling::wb {

// ---------------------------------------------------------------------------------------------
// Ground-truth simulator (tests, docs, `hapticlab measurement simulate`): human-like strokes on
// a sample whose physics has a chosen set of effects; noise on forces, positions, velocities
// and acceleration. The strokes, the inversion of the normal law for a commanded load, the Dahl
// bristle (explicit Euler, 20 substeps per sample) and the AR(2) vibration resonance are the
// simulator's; what each effect adds is its own truth hook (Effect::TruthNormal, ...), an
// implementation apart from the model's.
struct TruthParams {
  std::vector<std::string> effects;  ///< which effects the truth has (BaselineEffects() by default)
  double K1mm_N = 1.5;               ///< the core's normal force at 1 mm penetration [N]
  double vib_sigma = 2.0;            ///< the core's vibration excitation [m/s^2]
  /// The effects' truth parameters set away from their defaults (Effect::TruthSpecs):
  /// effect -> name -> value. Set / Get with the keys of workbench_params.hpp (key::kMuK,
  /// truth_key::kTileAmplitude, ...).
  std::map<std::string, std::map<std::string, double>> params;
  /// Out of the catalogue (tests of `diagnose`'s unexplained report): mu_k drifts linearly by
  /// this fraction over the recording (mu_k (1 + mu_drift (t / duration - 1/2))), and the
  /// stiffness varies over the surface (K1mm (1 + K_position_amp x / (area / 2))).
  double mu_drift = 0, K_position_amp = 0;
  double force_noise_N = 0.005, pos_noise_m = 0.2e-6, vel_noise_mps = 0.2e-3, acc_noise = 0.05;
  double duration_s = 30, rate_hz = 2000;
  double area_m = 0.04;  ///< strokes stay in a square of this side
  std::uint64_t seed = 1;
  bool Has(std::string_view e) const;
  void Set(ParamKey k, double value);
  /// The value set, else the effect's default. Precondition (HL_REQUIRE): the effect is in the
  /// catalogue and declares the parameter.
  double Get(ParamKey k) const;
};
struct SimulatedMeasurement {
  TruthParams truth;
  Measurement m;
  std::vector<double> fn_clean, ftx_clean, fty_clean;  ///< noise-free forces per row
  /// Per row, the vibration process: excitation variance, AR(2) a1, a2, sensor noise variance
  /// (the expected periodogram follows analytically).
  std::vector<std::array<double, 4>> acc_state;
};
/// Precondition (HL_REQUIRE): every effect of `t` is in the catalogue, and every parameter set
/// is one its effect declares, finite and within its bounds.
SimulatedMeasurement Simulate(const TruthParams& t);
/// The truth expressed as a workbench model (force channels; the vibration truth has another
/// form): the truth's parameters, the position field re-expanded on the replay's area.
Model TruthModel(const SimulatedMeasurement& sim, const Replay& r);
/// Noise floor on a split: the truth replayed through the measured (noisy) kinematics for the
/// force channels — no model can beat it on average — and, for vibration, E_s of the measured
/// band powers against their analytic expectation.
Errors NoiseFloor(const SimulatedMeasurement& sim, const Replay& r, Split split);

}  // namespace hapticlab::modeling::wb
