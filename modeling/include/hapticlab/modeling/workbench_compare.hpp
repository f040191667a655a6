#pragma once
/// @file Workbench `compare`: a model's errors against a measurement, overall and broken down
/// by regime (speed thresholds 0.5 and 3 mm/s), speed [mm/s], load [N], direction [deg],
/// position (3 x 3 tiles of the contact area), time (tenths of the recording) and, for
/// vibration, frequency band [Hz] (residuals in dB).

#include <map>
#include <string>
#include <vector>

#include "hapticlab/modeling/workbench_predict.hpp"

namespace hapticlab::modeling::wb {

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

}  // namespace hapticlab::modeling::wb
