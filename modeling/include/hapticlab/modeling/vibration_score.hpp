#pragma once
/// @file Any vibration model scored on any recording (issue #33): the model's synthesis at
/// the recording's (speed, force) against the recording preprocessed to the model's rate, by
/// E_s (eq. 3.1) and the level ratio. Models: a material model (its AR/ARMA bank - fitted or
/// imported from the Penn toolkit - or its neural model), a bank file written by
/// `model fit-vibration`, or a neural model file.

#include <cstdint>
#include <string>
#include <vector>

#include "hapticlab/modeling/vibration_recording.hpp"
#include "hapticlab/renderer/material.hpp"

namespace hapticlab::modeling {

/// Loads a material model, a bank file (a [vibration] table alone) or a neural model file
/// (topology = ...) as a material whose vibration is that model.
/// @throws InputError naming the file (also when it holds no vibration model).
renderer::MaterialModel LoadVibrationModel(const std::string& path);

struct ScoreOptions {
  bool level_normalised = false;  ///< scale the synthesis to the recording's RMS before E_s
  std::uint64_t seed = 1;         ///< synthesis seed
  double band_lo_hz = 20;         ///< the recording's band limit, as fit-vibration's
};

struct VibrationScore {
  std::string kind;  ///< "ar bank", "arma bank", "neural unified", "neural decomposed"
  double speed_mps = 0, force_N = 0;  ///< the condition synthesized
  bool condition_from_model = false;  ///< unlabelled recording, one-cell model: its cell's
  double es = 0;                      ///< E_s (after level normalisation when asked)
  double level_ratio = 0;             ///< RMS(synthesis) / RMS(recording), before any scaling
  double model_rate_hz = 0;
  /// false: a neural model trained on uncalibrated recordings (its file says
  /// `calibration = "uncalibrated"`): its level is in those recordings' units.
  bool model_calibrated = true;
};

/// Scores `m` on `r` (condition from the recording; an unlabelled one takes the condition of
/// a one-cell bank). @throws InputError naming the recording when it has no condition and
/// the model more than one, or when it is too short for E_s at the model's rate.
VibrationScore ScoreVibration(const renderer::MaterialModel& m, const Recording& r,
                              const ScoreOptions& o = {});

}  // namespace hapticlab::modeling
