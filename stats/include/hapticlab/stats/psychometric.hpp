#pragma once
/// @file Maximum-likelihood fits of psychometric functions (logistic, Weibull, cumulative
/// normal; psychophysics/psychometric.hpp) to binomial data, with the guess rate fixed by the
/// task, the lapse rate fixed or free, and parametric-bootstrap confidence intervals for the
/// threshold and the slope [Wichmann & Hill 2001, doi:10.3758/BF03194545].
///
/// The fit maximises sum_i k_i ln psi_i + (n_i - k_i) ln(1 - psi_i) over the linear
/// predictor eta = a + b g(x) by Fisher scoring (the MLE R's glm finds with psyphy's mafc
/// and 2asym links; checked to 1e-4 in tests/stats/psychometric_test.cpp); a free lapse rate
/// maximises the profile likelihood over lambda (golden section on [0, max_lapse]).

#include <cstdint>
#include <string>
#include <vector>

#include "hapticlab/core/solver_summary.hpp"
#include "hapticlab/psychophysics/psychometric.hpp"

namespace hapticlab::stats {

/// Binomial psychometric data: at stimulus x[i], k[i] positive answers (correct, or "yes") of
/// n[i] trials. Trials at equal x may be listed separately or pooled.
struct PsychometricData {
  std::vector<double> x;
  std::vector<int> n, k;
};

struct PsychometricFitOptions {
  psychophysics::Shape shape = psychophysics::Shape::kLogistic;
  double guess = 0.5;       ///< gamma, fixed by the task (1/m for m-AFC), dimensionless
  bool lapse_free = false;  ///< fit lambda in [0, max_lapse]
  double lapse = 0;         ///< lambda when fixed, dimensionless
  double max_lapse = 0.06;  ///< upper bound of a free lambda (Wichmann & Hill 2001)
  /// Why the options are unusable (empty when valid).
  bool IsValid(std::string* why) const;
};

/// A maximum-likelihood fit: the solver's summary (Newton iterations, cost = negative
/// log-likelihood including the binomial coefficients, `message` says why it is not usable,
/// or "converged") and the fitted function.
struct PsychometricFit : SolverSummary {
  bool usable = false;  ///< converged, finite and not degenerate (slope 0 or unbounded)
  psychophysics::PsychometricParams params;  ///< threshold, slope, guess, lapse
  double a = 0, b = 0;                       ///< linear predictor eta = a + b g(x)
  double log_likelihood = 0;  ///< including the binomial coefficients (as R's logLik)
  /// Residual deviance 2 (logL_saturated - logL), as R's deviance() of the glm fit.
  double deviance = 0;
  /// Standard errors of a and b from the inverse expected information at the estimate (R's
  /// vcov() of the glm fit, dispersion 1); conditional on the lapse rate when it is free.
  double se_a = 0, se_b = 0;
};

/// Data the model cannot describe (n < 1, k outside 0..n, x <= 0 for a Weibull, fewer than
/// two distinct stimuli) give an unusable fit whose `message` names the problem.
/// @throws PreconditionError when the options are invalid or x, n and k differ in length.
PsychometricFit FitPsychometric(const PsychometricData& data,
                                const PsychometricFitOptions& options);

struct BootstrapInterval {
  double lo = 0, hi = 0;
};
struct PsychometricBootstrap {
  int replicates = 0;  ///< usable refits
  int failed = 0;      ///< refits that did not converge (left out)
  double level = 0.95;
  BootstrapInterval threshold, slope;  ///< percentile intervals
  BootstrapInterval jnd;  ///< of StimulusAt(jnd_performance) when one was asked for, else NaN
  /// Of StimulusAt(p) for each p of `performances` (same order); a replicate whose lapse
  /// leaves p unreachable counts as +infinity, so an interval may end at inf.
  std::vector<BootstrapInterval> stimulus_at;
};

/// Parametric bootstrap: `replicates` data sets drawn from the fitted function at the same
/// stimuli and trial counts, each refitted with the same options; percentile intervals at
/// `level`; with `jnd_performance` in (guess, 1) also of the stimulus at that performance, and
/// of the stimulus at each of `performances` (each in (guess, 1)). Deterministic for a seed.
PsychometricBootstrap BootstrapPsychometric(const PsychometricData& data,
                                            const PsychometricFitOptions& options,
                                            const PsychometricFit& fit, int replicates,
                                            std::uint64_t seed, double level = 0.95,
                                            double jnd_performance = -1,
                                            const std::vector<double>& performances = {});

/// Pools trials with equal x (sorted by x): for binned plots and compact fits.
PsychometricData PoolByStimulus(const PsychometricData& d);

}  // namespace hapticlab::stats
