#pragma once
/// @file The friction channel's estimates checked, and corrected, by a parametric bootstrap
/// through the whole preprocessing (Efron & Tibshirani, "An Introduction to the Bootstrap",
/// 1993, ch. 6 and 10: the bootstrap estimate of bias). The friction replay does not see its
/// inputs as measured: the Coulomb level is the measured, smoothed normal force (its noise acts
/// through the bristle's saturation |F| <= mu_k f_load, an error in an input), the bristle follows
/// positions smoothed over a window chosen from the data, and the replay runs at a decimated
/// rate. Each leaves an error in mu_b of about 1 % on generated free-hand strokes
/// (docs/modeling-geometry-contact.md) that is systematic within a recording: it depends on the
/// recording's own strokes, so no resampling of the recording (the cluster jackknife) sees it,
/// and the intervals covered mu_b's truth in 16 of 20 seeds. Here the fitted model is replayed
/// at the recording's full rate along the recording's own smoothed path and load, the noise
/// measured in the recording is added (positions, velocities, tangential and normal forces),
/// and each copy goes through the same preprocessing and friction fit as the recording. The
/// copies' mean minus the fit is the pipeline's bias on this recording, their spread its
/// standard error. Hand-written: no Debian package runs a user-defined pipeline this way.

#include <cstdint>
#include <string>
#include <vector>

#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/workbench_fit.hpp"

namespace hapticlab::modeling::wb {

struct BootstrapOptions {
  int replicates = 20;          ///< simulated copies of the recording
  std::uint64_t seed = 0xb007;  ///< of the simulated noise (the result is reproducible)
};

/// One friction parameter before and after the correction.
struct BootstrapParam {
  std::string effect, name;
  double fit = 0;        ///< the fit on the data as measured
  double bias = 0;       ///< mean of the copies' fits minus the model they were simulated from
  double corrected = 0;  ///< fit - bias, held within the parameter's physical range
  /// The bias correction crossed the physical range (e.g. mu_b < 0): `corrected` is the bound,
  /// and the interval runs from it (ParamEstimate::at_bound is set).
  bool clamped = false;
  double jackknife_sd = 0, bootstrap_sd = 0;  ///< the fit's standard errors, each way
  double sd = 0;  ///< standard error of `corrected`: sqrt(max(jk^2, bs^2) + bs^2 / replicates)
};

/// The noise of a measurement, SD per row, from the rows in contact (f_z > `contact_force_N`):
/// the median absolute second difference / (0.6745 sqrt 6) over three consecutive rows (white
/// noise's second difference has variance 6 sigma^2; the median ignores the signal's own motion,
/// reversals and contact edges). 0 with fewer than 200 such rows.
struct MeasurementNoise {
  double position_m = 0, velocity_mps = 0, tangential_N = 0, load_N = 0;
};
MeasurementNoise EstimateNoise(const Measurement& m, double contact_force_N);

struct BootstrapReport {
  bool applied = false;
  std::string why_not;  ///< when not applied, in words
  MeasurementNoise noise;
  int replicates = 0;
  std::vector<BootstrapParam> params;
  std::string method;  ///< one sentence for reports
};

/// Corrects the friction channel's fit `friction` (fitted by Fit on PrepareReplay(m, replay)
/// with `fit`'s split; `model` holds the fitted values) by the parametric bootstrap above and
/// writes the corrected values into `model` and `friction` (value, sd, and the 95 % interval
/// with the fit's own t quantile). Not applied (returned with `why_not`) when the recording has
/// no measurable noise or too few rows, or a copy's fit is not usable.
BootstrapReport BootstrapFriction(Model* model, const Measurement& m, const ReplayOptions& replay,
                                  const FitOptions& fit, ChannelFit* friction,
                                  const BootstrapOptions& o = {});

}  // namespace hapticlab::modeling::wb
