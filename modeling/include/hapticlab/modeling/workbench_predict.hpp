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

/// One channel's error over the samples (windows) of a split.
struct ChannelErrors {
  bool present = false;   ///< the split had samples in contact (vibration: scored windows)
  double normalized = 0;  ///< the normalized error [1] (see Errors)
  double normalizer = 0;  ///< Σ f² [N²] over the samples (vibration: the window count)
  std::map<int, double> block_sse;  ///< time block -> SSE [N²] (vibration: Σ E_s [1])
};

/// Errors per channel, normalized so they can be summed: normal RMS / RMS(f_n), tangential
/// RMS(|Δf_t|) / RMS(|f_t|), vibration mean E_s (eq. 3.1 over band magnitudes). `overall` is
/// the mean of the channels present. Per-block sums support the significance test.
struct Errors {
  double overall = 0;
  ChannelErrors normal_force, friction, vibration;
  double normal_force_rms_N = 0;  ///< RMS of the normal-force residual over samples in contact
  double tangential_rms_N = 0;    ///< RMS of |tangential residual| over samples in contact
  double friction_ratio_rms = 0;  ///< RMS of the friction-ratio residual while sliding [1]
  const ChannelErrors& Of(Channel c) const;
  /// The normalized errors of the present channels (in Channel order, as reports list them).
  std::map<Channel, double> Normalized() const;
};
Errors ComputeErrors(const Replay& r, const Prediction& p, Split split);

}  // namespace hapticlab::modeling::wb
