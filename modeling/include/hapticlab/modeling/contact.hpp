#pragma once
/// @file Contact identification (dissertation ch. IV.3): one engine for `model fit-contact` and
/// the workbench. Friction is the vector Dahl model with Coulomb and viscous terms
/// (eqs. 4.6-4.7) replayed over the measured 2-D tangential path, initialised by Algorithm 1
/// (in its 2-D form) and refined jointly by Ceres; the normal force is Hunt-Crossley
/// (eq. 4.11) fitted on pokes with samples above 2 N discarded. Both are the workbench's
/// friction and normal channels (workbench.hpp), so `model fit-contact` and `hapticlab fit`
/// agree by construction. Uncertainties: delete-one-cluster jackknife over 3 s clusters of blocks;
/// the friction's bias-corrected, with standard errors at least the jackknife's, by a parametric
/// bootstrap through the preprocessing (workbench_bootstrap.hpp).

#include <string>

#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/modeling/workbench_bootstrap.hpp"

namespace hapticlab::modeling {

/// A parameter with its uncertainty.
struct Estimate {
  double value = 0;
  double sd = 0;              ///< standard error (cluster jackknife; 0 when unavailable)
  double lo95 = 0, hi95 = 0;  ///< 95 % interval
};

/// Algorithm 1 of the dissertation in 2-D: mu_k and mu_b from sliding samples by linear least
/// squares on the vector form of eq. 4.10, kappa from pre-sliding samples by least squares on
/// the vector form of eq. 4.9, alternated until every change is below `convergence`.
struct Algorithm1Result {
  double kappa_N_per_m = 0, mu_k = 0, mu_b_Ns_per_m = 0;
  int passes = 0;
  bool converged = false;
  int presliding_samples = 0, sliding_samples = 0;
};

struct ContactFitOptions {
  double presliding_speed_mps = wb::kPreslidingSpeed_mps;  ///< Tv1 (Algorithm 1)
  double sliding_speed_mps = wb::kSlidingSpeed_mps;        ///< Tv2
  double convergence = 1e-9;                               ///< TC
  double max_force_N = 2.0;  ///< poke samples above this are discarded (ch. IV.3.3)
  /// How the measurement is replayed (smoothing, rate). The default is the workbench's, so that
  /// `model fit-contact` and `hapticlab fit` agree; other values are for measuring the effect of
  /// the preprocessing on the estimates (tests/modeling/contact_test.cpp, Experiment).
  wb::ReplayOptions replay;
  /// The friction's Coulomb level from the fitted Hunt-Crossley law's prediction of the load
  /// (penetration and its rate) instead of the measured, smoothed load (errors in variables;
  /// see FitContact).
  bool load_from_normal_law = false;
  /// Correct the friction parameters for the preprocessing's bias, and take their standard
  /// errors, by a parametric bootstrap through it (workbench_bootstrap.hpp; not with
  /// load_from_normal_law).
  bool bootstrap = true;
  wb::BootstrapOptions bootstrap_options;
};

/// Algorithm 1 over the replay's samples in the split.
/// @throws InputError naming the file when there are too few pre-sliding or sliding samples.
Algorithm1Result AlgorithmOne(const wb::Replay& r, wb::Split split,
                              const ContactFitOptions& o = {});

struct ContactFit {
  // Renderer units ([contact] and [friction] of a material model).
  Estimate K;              ///< texture_K [N/m^n]
  Estimate B;              ///< texture_B [N s/m^(n+1)]
  Estimate n;              ///< texture_n (dimensionless)
  Estimate K1mm_N;         ///< force at 1 mm penetration [N] (the workbench's core)
  Estimate B1mm_Ns_per_m;  ///< damping at 1 mm [N s/m]
  Estimate kappa_N_per_m, mu_k, mu_b_Ns_per_m;
  Algorithm1Result algorithm1;
  wb::FitSummary friction_summary, normal_summary;
  double friction_rms_N = 0;  ///< RMS of the tangential residual (vector) over samples in contact
  double normal_rms_N = 0;    ///< RMS of the normal residual over the fitted poke samples
  int stroke_samples = 0, poke_samples = 0;
  std::string poke_source;  ///< where the Hunt-Crossley samples came from, in words
  std::string uncertainty_method;
  wb::BootstrapReport bootstrap;  ///< kappa, mu_k, mu_b's correction (`applied` or why not)
  bool IsUsable() const { return friction_summary.usable && normal_summary.usable; }
};

/// Friction from the strokes of `m` (all of it is replayed: pokes carry no sliding) and
/// Hunt-Crossley from pokes: `pokes` when given, else the samples of `m` that are pokes
/// (SplitStrokesAndPokes), else every sample of `m` in contact, up to `max_force_N`.
/// @throws InputError when there are too few stroke or poke samples.
ContactFit FitContact(const Measurement& m, const Measurement* pokes = nullptr,
                      const ContactFitOptions& o = {});

/// The effects FitContact fits: coulomb, viscous, dahl, hc-damping, hc-exponent.
std::vector<std::string> ContactEffects();

/// Samples of a measurement that are pokes (vertical motion, no sliding) and strokes (the rest).
void SplitStrokesAndPokes(const Measurement& m, Measurement* strokes, Measurement* pokes);

}  // namespace hapticlab::modeling
