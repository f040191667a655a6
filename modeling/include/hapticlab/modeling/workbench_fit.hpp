#pragma once
/// @file Workbench fitting: a model's parameters fitted to a Replay per channel (Ceres,
/// bounded, for the force channels; ridge least squares for the vibration log band powers),
/// with a solver summary and optional cluster-jackknife uncertainties.

#include <limits>
#include <string>
#include <vector>

#include "hapticlab/core/enum_names.hpp"
#include "hapticlab/core/solver_summary.hpp"
#include "hapticlab/modeling/workbench_predict.hpp"

namespace hapticlab::modeling::wb {

struct FitOptions {
  Split split = Split::kAll;
  bool normal = true, friction = true, vibration = true;  ///< channels to fit
  int max_iterations = 100;
  /// Compute uncertainties (delete-one-cluster jackknife over 3 s clusters of the split's blocks;
  /// see ChannelFit).
  bool uncertainty = false;
  /// Normal-force samples above this are not fitted (ch. IV.3.3 fits the texture layer on
  /// pokes up to 2 N); infinity: every sample in contact [N].
  double max_normal_force_N = std::numeric_limits<double>::infinity();
  /// When the friction channel has coulomb and dahl at their initial values (never fitted),
  /// start the Ceres refinement from Algorithm 1 (2-D form, contact.hpp).
  bool algorithm1_init = true;
};

/// How a channel's solve ended (Ceres' termination type, or not run at all).
enum class FitTermination { kConverged, kIterationLimit, kFailed, kNotRun };
inline constexpr EnumTable<FitTermination, 4> kFitTerminationNames{
    {{FitTermination::kConverged, "converged"},
     {FitTermination::kIterationLimit, "iteration limit"},
     {FitTermination::kFailed, "failed"},
     {FitTermination::kNotRun, "not run"}}};

/// Why a channel was not fitted (FitTermination::kNotRun); kNone for a solve that ran.
enum class FitNotRun {
  kNone,
  kNoFittedParameter,
  kTooFewSamples,
  kNoAcceleration,
  kTooFewVibrationWindows
};
inline constexpr EnumTable<FitNotRun, 5> kFitNotRunNames{
    {{FitNotRun::kNone, ""},
     {FitNotRun::kNoFittedParameter, "no fitted parameter"},
     {FitNotRun::kTooFewSamples, "too few samples"},
     {FitNotRun::kNoAcceleration, "no acceleration"},
     {FitNotRun::kTooFewVibrationWindows, "too few vibration windows"}}};

/// What one fit did, kept from Ceres' Summary (STYLE.md §6): a fit that stopped at its
/// iteration limit or with a parameter at a bound must not look like a converged one. The
/// solver's common report (core/solver_summary.hpp: converged, iterations, costs as 1/2 sum of
/// squared residuals [N^2 or ln^2], the solver's own message) plus the workbench's context.
struct FitSummary : SolverSummary {
  Channel channel = Channel::kNormal;  ///< the channel fitted
  std::string method;  ///< "ceres (numeric derivatives of the replay)" or "linear least squares"
  FitTermination termination = FitTermination::kNotRun;
  FitNotRun not_run = FitNotRun::kNone;  ///< why, when termination is kNotRun
  std::vector<std::string> at_bounds;    ///< "effect.param at its lower|upper bound (value)"
  bool usable = false;                   ///< converged (or a linear solve) with a finite cost
  bool IsUsable() const { return usable; }
};

/// The termination in words, as reports print it: "converged", "iteration limit", "failed" or
/// "not run (too few samples)" (the reason in parentheses).
std::string TerminationText(const FitSummary& s);

/// One fitted parameter with its uncertainty.
struct ParamEstimate {
  std::string effect, name;
  double value = 0;
  double sd = 0;              ///< standard error (0 when not computed)
  double lo95 = 0, hi95 = 0;  ///< 95 % interval: value -+ t(0.975, clusters - 1) sd, within
                              ///< [bound_lo, bound_hi]
  /// The parameter's physical range (its ParamSpec's [lo, hi]): the estimate and its interval
  /// stay inside it after every correction (the bootstrap's bias correction included).
  double bound_lo = -1e300, bound_hi = 1e300;
  bool at_bound = false;
};

/// A fitted channel. Uncertainty (FitOptions::uncertainty) is a delete-one-cluster jackknife
/// (CR3), cov = (G-1)/G sum_g (d_g - mean d)(d_g - mean d)' with d_g = (J'J - J_g'J_g)^-1 J_g' r_g
/// the one-step change of leaving cluster g out, the clusters being 3 consecutive 1 s blocks of
/// the split (a cluster spans several strokes): it holds when residuals are correlated within a
/// stroke and their variance changes with load or speed, which the plain (J'J)^-1 sigma^2 does
/// not, and unlike the CR0 sandwich it is not biased low with few clusters.
struct ChannelFit {
  Channel channel = Channel::kNormal;
  FitSummary summary;
  std::vector<ParamEstimate> params;  ///< fitted parameters in the order of the effects
  std::vector<double> covariance;     ///< params.size()^2, row-major (empty without uncertainty)
  int clusters = 0;                   ///< clusters in the jackknife
  int samples = 0;                    ///< force samples (or windows) fitted
};
struct FitReport {
  std::vector<ChannelFit> channels;
  /// Every channel's fit usable.
  bool IsUsable() const;
  /// The channel's fit, or nullptr.
  const ChannelFit* Find(Channel c) const;
  ChannelFit* Find(Channel c);
};

/// Fits the model's parameters on the split (Ceres for forces, linear least squares for the
/// vibration log band powers). Returns one ChannelFit per channel fitted.
FitReport Fit(Model* m, const Replay& r, const FitOptions& o = {});

}  // namespace hapticlab::modeling::wb
