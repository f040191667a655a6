#pragma once
/// @file Workbench prediction and errors: a model replayed over a Replay's kinematics gives
/// the normal force [N], the surface's tangential force on the tool in the sample frame [N] and
/// vibration band powers [(m/s^2)^2 per bin]; residuals are measured minus predicted.

#include <map>
#include <string>
#include <vector>

#include "hapticlab/modeling/workbench_model.hpp"

namespace hapticlab::modeling::wb {

/// Predictions for every force sample and vibration window.
struct Prediction {
  std::vector<double> fn_N, ftx_N, fty_N;
  std::vector<std::vector<double>> band_power;  ///< per window, per band
};
Prediction Predict(const Model& m, const Replay& r);

/// Residuals (measured minus predicted) in the quantities the evidence reads.
struct Residuals {
  std::vector<double> normal_N;    ///< f_n,meas - f_n,pred (0 out of contact)
  std::vector<double> friction_N;  ///< friction along the motion, measured - predicted
  std::vector<double> ratio;       ///< friction ratio measured - predicted (sliding samples)
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
  std::map<std::string, double> channel;  ///< ChannelName -> normalized error
  std::map<std::string, double> rms;      ///< normal_force_N, tangential_N, friction_ratio
  std::map<std::string, std::map<int, double>> block_sse;  ///< channel -> block -> SSE (or Σ E_s)
  std::map<std::string, double> norm;  ///< channel -> normalizer (Σ f² or window count)
};
Errors ComputeErrors(const Replay& r, const Prediction& p, Split split);

}  // namespace hapticlab::modeling::wb
