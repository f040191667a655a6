#pragma once
/// @file Friction (Dahl) and stiffness (Hunt-Crossley) identification from stylus strokes and
/// pokes (dissertation ch. IV.3): Algorithm 1 for the Dahl model, then a batch refinement of
/// all friction parameters with Ceres; Hunt-Crossley K, B, n by nonlinear least squares
/// (Ceres) on pokes with samples above 2 N discarded. Uncertainties from Ceres' covariance.

#include <string>

#include "hapticlab/core/measurement.hpp"
#include "hapticlab/renderer/material.hpp"

namespace hapticlab::modeling {

struct Estimate {
  double value = 0;
  double sd = 0;  ///< standard error from the Ceres covariance (0 when unavailable)
};

struct DahlFit {
  Estimate kappa_N_per_m, mu_k, mu_b_Ns_per_m;
  int algorithm1_passes = 0;     ///< passes of Algorithm 1 until every change < 1e-9
  bool algorithm1_converged = false;
  double rms_residual_N = 0;     ///< friction residual after the batch refinement
  int presliding_samples = 0, sliding_samples = 0;
};

struct HuntCrossleyFit {
  Estimate K, B, n;
  double rms_residual_N = 0;
  int samples = 0;               ///< in contact and at most `max_force_N`
};

struct ContactFitOptions {
  double presliding_speed_mps = 0.5e-3;  ///< Tv1 (Algorithm 1)
  double sliding_speed_mps = 3e-3;       ///< Tv2
  double convergence = 1e-9;             ///< TC
  double max_force_N = 2.0;              ///< poke samples above this are discarded (ch. IV.3.3)
};

/// Dahl friction from strokes on a flat sample (surface at z = 0, forces the surface exerts
/// on the tool). The motion axis is the principal direction of the tangential velocity.
/// @throws InputError naming the file when there are too few pre-sliding or sliding samples.
DahlFit FitDahl(const Measurement& strokes, const ContactFitOptions& o = {});

/// Hunt-Crossley from pokes: penetration d = -z, rate -vz, force fz; samples in contact and
/// at most max_force_N. @throws InputError when there are too few.
HuntCrossleyFit FitHuntCrossley(const Measurement& pokes, const ContactFitOptions& o = {});

/// Samples of a measurement that are pokes (vertical motion, no sliding) and strokes (the rest).
void SplitStrokesAndPokes(const Measurement& m, Measurement* strokes, Measurement* pokes);

}  // namespace hapticlab::modeling
