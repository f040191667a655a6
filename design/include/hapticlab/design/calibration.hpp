#pragma once
/// @file Calibration of the simulated observer against published statistics
/// (`hapticlab study calibrate`; docs/studies.md "Calibrating the observer").
///
/// Targets file (TOML):
///   [fit]     seed, simulations (simulated studies per protocol per evaluation), pool
///             (participants recorded through the runner per protocol), sweeps, observer
///             (file written, relative to the targets file), start (observer file to start from)
///   [[protocol]] id, file (relative), participants (per simulated study)
///   [[param]]    name ("upper", "lower", "range_sd", "lapse_rate", a perceptual scale
///                "scale_vibration" | "scale_fluctuation" | "scale_friction" | "scale_stiffness" |
///                "scale_pattern" (lo, hi within [0.001, 10]), or "CRITERION.FIELD" with
///                FIELD sensitivity | offset_sd | material_sd | method_sd | noise_sd), lo, hi,
///                step. A candidate with other perceptual scales than the recording observer's
///                re-measures each recorded trial's feature distances (FeltTrial::felt).
///   [[target]]   protocol (an id), statistic, value, weight, and per statistic:
///                pes: criterion, effect (method | material | method:material) — mean partial eta^2
///                method_mean: criterion, method — mean main-phase score of the method
///                sd: criterion — SD of all main-phase scores of a study
///                upper_limit / lower_limit: criterion — mean reference-phase score of same /
///                different real-real pairs
/// Loss = sum of weight x (achieved - value)^2, each statistic averaged over the simulations.

#include <functional>
#include <string>
#include <vector>

#include "hapticlab/design/power_pool.hpp"
#include "hapticlab/sim/sim_lab.hpp"

namespace hapticlab::design {

struct CalibrationTarget {
  std::string protocol, statistic, criterion, effect, method;
  double value = 0, weight = 1;
  int line = 0;
};
struct CalibrationProtocol {
  std::string id, file;
  int participants = 15;
};
struct CalibrationParam {
  std::string name;
  double lo = 0, hi = 1, step = 0.1;
};
struct CalibrationSpec {
  std::string path;
  std::uint64_t seed = 1;
  int simulations = 16, pool = 6, sweeps = 10;
  int pool_first =
      0;  ///< plan index of the first pool participant (not in the file; tests hold out the fit's)
  std::string observer_out, start;
  std::vector<CalibrationProtocol> protocols;
  std::vector<CalibrationParam> params;
  std::vector<CalibrationTarget> targets;
};
/// Whether `name` is one of the observer's perceptual scales (ObserverParams::scale_*).
bool IsScaleParam(const std::string& name);
/// @throws InputError listing every problem (file, line, key)
CalibrationSpec LoadCalibration(const std::string& path);

struct CalibrationState {
  std::vector<FeltPool> pools;  ///< per protocol, in spec order
  sim::ObserverParams start;    ///< the start observer
};
/// Records each protocol's pool through the runner (the slow part) and loads the start observer.
CalibrationState PrepareCalibration(const CalibrationSpec& spec,
                                    const std::function<void(const std::string&)>& log);

struct CalibrationRow {
  std::string protocol, label;
  double target = 0, weight = 0, achieved = 0;
};
/// Loss of `observer`; with `rows`, also each target's achieved value.
double EvaluateCalibration(const CalibrationState& state, const CalibrationSpec& spec,
                           const sim::ObserverParams& observer, std::vector<CalibrationRow>* rows,
                           int threads = 2);

}  // namespace hapticlab::design
