#pragma once
/// @file The model-versus-measurement workbench (DESIGN.md §4): a material model is a set of
/// named physical effects with parameters; the workbench replays measured kinematics through
/// it, breaks the error down by regime, fits effects, and ranks the effects a model lacks by
/// held-out error reduction.
///
/// Three channels are predicted from the replayed kinematics:
///  - normal force   f_n = K d^n + B d^n d_dot + extra(d)            (Hunt-Crossley, eq. 4.11)
///  - friction       the surface's tangential force -(F_D + mu_b v), F_D a vector Dahl bristle
///                   whose Coulomb level is f_C = f_n,meas (mu_k S + mu_add)   (eqs. 4.6-4.7)
///  - vibration      log band powers of 0.128 s windows as a linear model in features of the
///                   window's speed, load and direction (the workbench's form of the AR bank
///                   over speed x force; exported to an AR bank when the model is written).
/// Each effect adds terms to one channel; see docs/workbench.md and effects/*.cpp.

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "hapticlab/core/measurement.hpp"

namespace hapticlab::modeling::wb {

enum class Channel { kNormal, kFriction, kVibration };
const char* ChannelName(Channel c);  ///< "normal_force", "friction", "vibration"

/// A measurement prepared for replay: force samples (decimated to <= max_force_rate_hz) and
/// vibration windows, each tagged with its time block (train/held-out split).
struct Replay {
  std::string file;
  double rate_hz = 0;        ///< rate of the force samples after decimation [Hz]
  double block_s = 1.0;      ///< length of a time block of the split [s]
  struct Sample {
    double t_s, x_m, y_m, d_m, ddot_mps, vx_mps, vy_mps, speed_mps, dir_rad, fn_N, ftx_N, fty_N;
    /// Measured normal force averaged over ReplayOptions::load_smoothing_s (rows in contact):
    /// the load that sets the Coulomb level. Raw sensor noise through the bristle's saturation
    /// (|F| <= f_C) would bias the friction level low, and a fitted mu_k high.
    double fload_N;
    bool contact;
    int block;
    int row;  ///< index of the measurement row
  };
  std::vector<Sample> s;
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;  ///< bounds of the positions in contact
  double position_resolution_m = 1e-6;  ///< the Dahl bristle follows the tool through a play of this width [m]

  bool has_vibration = false;
  double acc_rate_hz = 0;
  std::vector<double> band_lo_hz, band_hi_hz;  ///< log-spaced analysis bands
  struct Window {
    double t_s, speed_mps, force_N;
    std::array<double, 4> dir;  ///< speed-weighted means of cos φ, sin φ, cos 2φ, sin 2φ
    std::vector<double> band_power;  ///< mean periodogram power per band [(m/s^2)^2 per bin]
    int block;
    int row0, rows;  ///< measurement rows of the window
  };
  std::vector<Window> windows;  ///< steady windows in contact with mean speed >= 1 cm/s
};

struct ReplayOptions {
  double max_force_rate_hz = 500;  ///< force samples are decimated to at most this rate
  double block_s = 1.0;            ///< split blocks: even blocks train, odd blocks held out
  double window_s = 0.128;         ///< vibration window (rounded to a power of two samples)
  int bands = 8;                   ///< log-spaced bands from 20 Hz to min(1000 Hz, 0.45 rate)
  double contact_force_N = 0.02;   ///< a sample is in contact when f_n exceeds this
  double min_speed_mps = 0.01;     ///< vibration windows below this speed are not scored
  double max_variation = 0.35;     ///< windows whose speed or load varies more (SD / mean) are not scored
  /// Displacements below this are sensor noise for the Dahl bristle (an encoder's resolution):
  /// without it, position noise at rest would random-walk the pre-sliding state to zero.
  /// 0 (default): 4 times the position noise estimated from the rows at rest (median absolute
  /// second difference), within 0.05-5 um; 1 um when there are too few rows at rest.
  double position_resolution_m = 0;
  double load_smoothing_s = 0.02;  ///< window of Sample::fload_N [s]
  /// Sample::fload_N by a quadratic Savitzky-Golay fit over load_smoothing_s where the whole
  /// window is in contact (a moving average flattens the load where it curves); false: the mean.
  bool load_savgol = true;
  /// Sample::x_m / y_m (what the Dahl bristle follows) by a quadratic Savitzky-Golay fit over
  /// this window [s]; an estimated position resolution is scaled to the smoothed noise. 0: raw.
  double position_smoothing_s = 0.02;
  std::vector<double> band_edges_hz;  ///< explicit band edges (a model's); empty: log-spaced
};

/// Prepares a measurement (vibration windows hop by a quarter window). @throws InputError when it has no samples in contact.
Replay PrepareReplay(const Measurement& m, const ReplayOptions& o = {});

/// One parameter of an effect. Fitted parameters are optimized (Ceres) within [lo, hi]; fixed
/// ones (e.g. the tile grid's bounds) are set from the data when the effect is added.
struct ParamSpec {
  std::string name, unit;
  double init = 0, lo = -1e300, hi = 1e300;
  double scale = 1;     ///< typical magnitude (the optimizer works on value / scale)
  bool fitted = true;
  std::string doc;
};

/// Per-sample terms of the normal-force channel that effects set:
/// f_n = (d / 1 mm)^n (K + B d_dot) + extra_N, with K the force at 1 mm [N] and B the damping
/// at 1 mm [N s/m] (well-conditioned for fitting whatever n is).
struct NormalTerms {
  double K = 0, n = 1, B = 0, extra_N = 0;
};
/// Per-sample terms of the friction channel: f_C = f_n (mu_k * mu_scale + mu_add);
/// kappa = 0 means no pre-sliding (ideal Coulomb, smoothed over 0.5 mm/s).
struct FrictionTerms {
  double mu_k = 0, mu_scale = 1, mu_add = 0, kappa = 0, mu_b = 0;
};

struct Residuals;

/// What the current model's residuals say about an effect: the pattern as measured, and the
/// cause it would point to. Reports assert the cause only for supported effects.
struct EvidenceNote {
  std::string pattern;      ///< the residual pattern in words with numbers (no causal claim)
  std::string cause;        ///< what the pattern means when the effect is supported
  bool contradicts = false; ///< the pattern is not the one this effect produces (or is absent)
  std::string Sentence(bool supported) const {
    return supported && !cause.empty() ? pattern + ": " + cause : pattern;
  }
};

/// A physical effect of the catalogue. Implementations live in modeling/src/effects/, one
/// file each, registered in effects/registry.cpp.
class Effect {
 public:
  virtual ~Effect() = default;
  virtual std::string_view name() const = 0;
  virtual Channel channel() const = 0;
  /// One paragraph: the physics, the formula, when it matters.
  virtual std::string_view description() const = 0;
  /// Effects this one modifies (e.g. dahl needs coulomb).
  virtual std::vector<std::string_view> requires_effects() const { return {}; }
  /// Its parameters with initial (neutral) values from the data.
  virtual std::vector<ParamSpec> Params(const Replay& r) const = 0;
  virtual void Normal(const double* /*p*/, const Replay::Sample& /*s*/, NormalTerms& /*t*/) const {}
  virtual void Friction(const double* /*p*/, const Replay::Sample& /*s*/, FrictionTerms& /*t*/) const {}
  /// Vibration effects add regression columns for the log band powers.
  virtual int VibrationColumns() const { return 0; }
  virtual void VibrationFeatures(const double* /*p*/, const Replay::Window& /*w*/, double* /*out*/) const {}
  /// What pattern of the current model's residuals points to this effect, and whether the
  /// residuals show it.
  virtual EvidenceNote Evidence(const Replay& r, const Residuals& res) const = 0;
};

/// The catalogue, in a fixed order. The core ("contact": K and the vibration intercept) is
/// not an entry: every model has it.
const std::vector<std::unique_ptr<Effect>>& Catalogue();
/// The entry named `name`, or nullptr.
const Effect* FindEffect(std::string_view name);
/// The thesis's model: coulomb, viscous, dahl, hc-damping, hc-exponent, vibration-speed,
/// vibration-force (Coulomb + viscous + Dahl friction, Hunt-Crossley with damping, AR bank
/// over speed x force).
std::vector<std::string> BaselineEffects();

/// A model: effect names and every parameter's values (fitted and fixed). Vibration
/// coefficients are stored as "coef" (bands x columns, row-major) per vibration effect and
/// under the core; "core" holds K and the intercepts.
struct Model {
  std::string name;
  std::vector<std::string> effects;
  std::map<std::string, std::map<std::string, double>> params;  ///< effect -> name -> value
  std::map<std::string, std::vector<double>> coef;              ///< vibration coefficients
  std::vector<double> band_edges_hz;  ///< bands the vibration coefficients refer to
  bool HasVibration() const { return coef.count("core") > 0; }
  bool Has(std::string_view e) const;
};

/// Adds effects (with their dependencies) to a model, initializing their parameters from the
/// data. @throws std::invalid_argument for an unknown name (listing the catalogue).
void AddEffects(Model* m, const std::vector<std::string>& names, const Replay& r);

/// Predictions for every force sample and vibration window.
struct Prediction {
  std::vector<double> fn_N, ftx_N, fty_N;
  std::vector<std::vector<double>> band_power;  ///< per window, per band
};
Prediction Predict(const Model& m, const Replay& r);

/// Residuals (measured minus predicted) in the quantities the evidence reads.
struct Residuals {
  std::vector<double> normal_N;     ///< f_n,meas - f_n,pred (0 out of contact)
  std::vector<double> friction_N;   ///< friction along the motion, measured - predicted
  std::vector<double> ratio;        ///< friction ratio measured - predicted (sliding samples)
  std::vector<std::vector<double>> log_band;  ///< ln(measured / predicted band power)
};
Residuals ComputeResiduals(const Model& m, const Replay& r, const Prediction& p);

/// Which samples count: all, the training blocks (even) or the held-out blocks (odd).
enum class Split { kAll, kTrain, kHeldOut };

/// Errors per channel, normalized so they can be summed: normal RMS / RMS(f_n), tangential
/// RMS(|Δf_t|) / RMS(|f_t|), vibration mean E_s (eq. 3.1 over band magnitudes). `overall` is
/// the mean of the channels present. Per-block sums support the significance test.
struct Errors {
  double overall = 0;
  std::map<std::string, double> channel;       ///< ChannelName -> normalized error
  std::map<std::string, double> rms;           ///< normal_force_N, tangential_N, friction_ratio
  std::map<std::string, std::map<int, double>> block_sse;  ///< channel -> block -> SSE (or Σ E_s)
  std::map<std::string, double> norm;          ///< channel -> normalizer (Σ f² or window count)
};
Errors ComputeErrors(const Replay& r, const Prediction& p, Split split);

struct FitOptions {
  Split split = Split::kAll;
  bool normal = true, friction = true, vibration = true;  ///< channels to fit
  int max_iterations = 100;
  /// Compute uncertainties (delete-one-cluster jackknife over 3 s clusters of the split's blocks; see ChannelFit).
  bool uncertainty = false;
  /// Normal-force samples above this are not fitted (ch. IV.3.3 fits the texture layer on
  /// pokes up to 2 N); infinity: every sample in contact [N].
  double max_normal_force_N = std::numeric_limits<double>::infinity();
  /// When the friction channel has coulomb and dahl at their initial values (never fitted),
  /// start the Ceres refinement from Algorithm 1 (2-D form, contact.hpp).
  bool algorithm1_init = true;
};

/// What one fit did, kept from Ceres' Summary (STYLE.md §6): a fit that stopped at its
/// iteration limit or with a parameter at a bound must not look like a converged one.
struct FitSummary {
  std::string what;          ///< channel name ("friction", "normal_force", "vibration")
  std::string method;        ///< "ceres (numeric derivatives of the replay)" or "linear least squares"
  std::string termination;   ///< "converged", "iteration limit", "failed", "not run (...)"
  std::string message;       ///< the solver's own message
  int iterations = 0;
  double initial_cost = 0;   ///< 1/2 sum of squared residuals at the start [N^2 or ln^2]
  double final_cost = 0;     ///< same at the end
  std::vector<std::string> at_bounds;  ///< "effect.param at its lower|upper bound (value)"
  bool usable = false;       ///< converged (or a linear solve) with a finite cost
  bool IsUsable() const { return usable; }
};

/// One fitted parameter with its uncertainty.
struct ParamEstimate {
  std::string effect, name;
  double value = 0;
  double sd = 0;                 ///< standard error (0 when not computed)
  double lo95 = 0, hi95 = 0;     ///< 95 % interval: value -+ t(0.975, clusters - 1) sd
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
};

/// Fits the model's parameters on the split (Ceres for forces, linear least squares for the
/// vibration log band powers). Returns one ChannelFit per channel fitted.
FitReport Fit(Model* m, const Replay& r, const FitOptions& o = {});

/// `compare`: errors overall and by regime.
struct BinRow {
  std::string label;
  double center = 0;
  int n = 0;
  double mean = 0, rms = 0;  ///< residual in the dimension's quantity
};
struct Comparison {
  Errors errors;
  /// dimension -> rows. Dimensions: regime, speed, load, direction, position, time (friction
  /// and normal residuals), band (vibration, per frequency band), vib_speed, vib_load.
  std::map<std::string, std::map<std::string, std::vector<BinRow>>> breakdown;
};
Comparison Compare(const Model& m, const Replay& r);

/// `diagnose`: every catalogue effect the model lacks, fitted on the training blocks and scored
/// on the held-out blocks.
struct Candidate {
  std::string effect;
  std::string channel;
  double error_after = 0;       ///< held-out overall error with the effect
  double error_reduction = 0;   ///< baseline_error - error_after
  double relative_reduction = 0;  ///< of the channel's held-out error
  double t_statistic = 0;       ///< paired over held-out blocks
  /// Error falls by the threshold, t above its threshold, the fit usable, none of the effect's
  /// parameters at a bound, and its own evidence does not contradict it.
  bool supported = false;
  std::map<std::string, double> params;
  /// The residual pattern; the cause it points to is asserted only when supported.
  std::string evidence;
  std::vector<std::string> confounded_with;
  FitSummary fit;                     ///< the candidate's channel refit
  std::vector<std::string> rejected;  ///< why a candidate that passed the numbers is not supported
};

/// Held-out error of one channel against its noise floor, estimated from the measurement
/// itself (force channels: sensor noise from the median absolute second difference of each
/// force component; vibration: the spread of a band-averaged Hann periodogram about its mean).
struct UnexplainedChannel {
  std::string channel;
  double error = 0, noise_floor = 0, ratio = 0;
};
/// How much of a channel's residual variance one axis explains (between-bin over total sum of
/// squares), with the shape of the dependence in words.
struct ResidualAxis {
  std::string axis;     ///< time, speed, load, direction, position, regime, band
  std::string channel;
  double share = 0;     ///< 0..1
  std::string description;
};
struct Unexplained {
  std::vector<UnexplainedChannel> channels;
  std::vector<ResidualAxis> axes;  ///< channels above the threshold first, then by share, descending
  /// No candidate supported, yet some channel's error is at least `unexplained_ratio` times its floor.
  bool flagged = false;
  std::string summary;  ///< one paragraph: what is unexplained, where it lives, what would be needed
};

struct Diagnosis {
  double baseline_error = 0;
  std::map<std::string, double> baseline_channel;
  std::vector<Candidate> candidates;  ///< sorted by error_reduction, descending
  Unexplained unexplained;
};
struct DiagnoseOptions {
  double min_relative_reduction = 0.02;  ///< of the channel's held-out error
  double min_t = 3.0;                    ///< paired t over held-out blocks
  double unexplained_ratio = 1.5;        ///< a channel's error / noise floor above which it is unexplained
  int threads = 0;                       ///< candidates fitted in parallel; 0: all cores
  /// Called after each candidate (effect, done, total), from the worker threads.
  std::function<void(const std::string&, int, int)> progress;
};
Diagnosis Diagnose(const Model& m, const Replay& r, const DiagnoseOptions& o = {});

/// The noise floor of each channel's normalized error on the split, estimated from the
/// measurement alone (see UnexplainedChannel). With a model, the noise of the measured
/// velocities (same estimator) is added through the model's sensitivity to them (the damping
/// and viscous terms), as the model sees it when replayed.
std::map<std::string, double> EstimateNoiseFloor(const Replay& r, Split split, const Model* m = nullptr);

/// Where a model's residual lives: every axis of every channel present, by share.
std::vector<ResidualAxis> RankResidualAxes(const Model& m, const Replay& r, const Prediction& p);

/// Model files: a material TOML (renderer-loadable) with `effects = [...]` and a `[workbench]`
/// table holding every effect's parameters; renderer materials without it are read from their
/// [contact] and [friction] tables.
Model LoadModel(const std::string& path);
/// Writes the model as a material TOML. With `r` and vibration fitted, an AR bank over the
/// grid of speed x force is derived from the band spectra (see docs/workbench.md).
void SaveModel(const Model& m, const std::string& path, const Replay* r = nullptr);

/// `measurement check`: duration, rate, ranges, gaps.
struct MeasurementSummary {
  double duration_s = 0, rate_hz = 0, max_gap_s = 0;
  int samples = 0, gaps = 0, contact_samples = 0;
  std::map<std::string, std::pair<double, double>> ranges;  ///< column -> (min, max)
  std::vector<std::string> warnings;
};
MeasurementSummary Summarize(const Measurement& m);

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
  double load_alpha = 0.7;                            ///< f_C ∝ f_n^alpha
  double tile_amp = 0.25;                             ///< µ varies by about ± this over the area
  double vib_sigma = 2.0, vib_speed_exp = 1.0, vib_force_exp = 0.8, vib_dir_amp = 0.8;
  double wavelength_m = 0.4e-3;                       ///< spatial period of the micro-geometry
  /// Out of the catalogue (tests of `diagnose`'s unexplained report): mu_k drifts linearly by
  /// this fraction over the recording (mu_k (1 + mu_drift (t / duration - 1/2))), and the
  /// stiffness varies over the surface (K1mm (1 + K_position_amp x / (area / 2))).
  double mu_drift = 0, K_position_amp = 0;
  double force_noise_N = 0.005, pos_noise_m = 0.2e-6, vel_noise_mps = 0.2e-3, acc_noise = 0.05;
  double duration_s = 30, rate_hz = 2000;
  double area_m = 0.04;                               ///< strokes stay in a square of this side
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
