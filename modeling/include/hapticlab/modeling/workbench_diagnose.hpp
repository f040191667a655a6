#pragma once
/// @file Workbench `diagnose`: every catalogue effect a model lacks, fitted on the training
/// blocks (even 1 s blocks) and scored on the held-out blocks (odd), and what no effect explains
/// (each channel's held-out error against its noise floor; where the residual lives).

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "hapticlab/modeling/workbench_fit.hpp"
#include "hapticlab/modeling/workbench_vibration.hpp"

namespace hapticlab::modeling::wb {

/// `diagnose`: every catalogue effect the model lacks, fitted on the training blocks and scored
/// on the held-out blocks.
struct Candidate {
  std::string effect;
  Channel channel = Channel::kNormal;
  double error_after = 0;         ///< held-out overall error with the effect
  double error_reduction = 0;     ///< baseline_error - error_after
  double relative_reduction = 0;  ///< of the channel's held-out error
  double t_statistic = 0;         ///< paired over held-out blocks
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
  Channel channel = Channel::kNormal;
  double error = 0, noise_floor = 0, ratio = 0;
};
/// How much of a channel's residual variance one axis explains (between-bin over total sum of
/// squares), with the shape of the dependence in words.
struct ResidualAxis {
  std::string axis;  ///< time, speed, load, direction, position, regime, band
  Channel channel = Channel::kNormal;
  double share = 0;  ///< 0..1
  std::string description;
};
struct Unexplained {
  std::vector<UnexplainedChannel> channels;
  std::vector<ResidualAxis>
      axes;  ///< channels above the threshold first, then by share, descending
  /// No candidate supported, yet some channel's error is at least `unexplained_ratio` times its
  /// floor.
  bool flagged = false;
  std::string
      summary;  ///< one paragraph: what is unexplained, where it lives, what would be needed
};

struct Diagnosis {
  double baseline_error = 0;
  std::map<Channel, double> baseline_channel;
  std::vector<Candidate> candidates;  ///< sorted by error_reduction, descending
  Unexplained unexplained;
  /// The baseline's held-out vibration E_s by speed and force (empty without vibration).
  std::vector<EsCell> vibration_by_condition;
};
struct DiagnoseOptions {
  double min_relative_reduction = 0.02;  ///< of the channel's held-out error
  double min_t = 3.0;                    ///< paired t over held-out blocks
  double unexplained_ratio =
      1.5;          ///< a channel's error / noise floor above which it is unexplained
  int threads = 0;  ///< candidates fitted in parallel; 0: all cores
  /// Called after each candidate (effect, done, total), from the worker threads.
  std::function<void(const std::string&, int, int)> progress;
};
Diagnosis Diagnose(const Model& m, const Replay& r, const DiagnoseOptions& o = {});

/// The noise floor of each channel's normalized error on the split, estimated from the
/// measurement alone (see UnexplainedChannel). With a model, the noise of the measured
/// velocities (same estimator) is added through the model's sensitivity to them (the damping
/// and viscous terms), as the model sees it when replayed.
std::map<Channel, double> EstimateNoiseFloor(const Replay& r, Split split,
                                             const Model* m = nullptr);

/// Where a model's residual lives: every axis of every channel present, by share.
std::vector<ResidualAxis> RankResidualAxes(const Model& m, const Replay& r, const Prediction& p);

/// The unexplained report of `Diagnose`: each channel of `held_out_errors` (the model's errors on
/// the held-out split, predictions `p`) against its noise floor, the residual axes ranked (channels
/// above `unexplained_ratio` times their floor first), flagged when `any_supported` is false and
/// some channel is above.
Unexplained ExplainResidual(const Model& m, const Replay& r, const Prediction& p,
                            const Errors& held_out_errors, bool any_supported,
                            double unexplained_ratio);

}  // namespace hapticlab::modeling::wb
