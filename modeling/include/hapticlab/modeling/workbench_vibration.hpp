#pragma once
/// @file The workbench scores vibration models it does not fit (issue #33): a renderer
/// material's AR/ARMA bank (fitted by `model fit-vibration` or imported from the Penn toolkit)
/// or its neural model, replayed over a measurement's vibration windows. The predicted band
/// power of a window is the model's spectrum at the window's (speed, force) in the window's
/// units [(m/s^2)^2 per FFT bin of the measurement]: S(f) fs_meas / fs_model, with S the model's
/// per-sample power spectrum at its own rate fs_model. For a bank S is exact (the interpolated
/// filter's gain^2 sigma^2 |B|^2 / |A|^2); for a neural model it is a Welch estimate of its
/// synthesis at the window's condition rounded to 5 % steps of speed and force. A window slower
/// than the model's switch-off speed is scored at that speed.

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "hapticlab/modeling/workbench_predict.hpp"

namespace hapticlab::modeling::wb {

/// When `path` is a renderer material whose vibration is an AR bank or a neural model (and `m`
/// has no band model of its own), sets m->vibration_model to it and returns what it is in words
/// ("an AR bank (9 cells, 2000 Hz)"); else returns "" and leaves `m` alone.
/// @throws InputError naming the file when it does not load as a material.
std::string AttachVibrationModel(Model* m, const std::string& path);

/// The highest band edge at which a fixed vibration model can be scored [Hz]: 0.45 of its rate
/// (ReplayOptions::max_band_hz).
double VibrationModelTopHz(const renderer::MaterialModel& vm);

/// A neural model's Welch spectra by rounded condition, filled by PredictModelBands (thread-safe).
struct VibrationSpectra {
  std::mutex mu;
  std::map<std::pair<long, long>, std::vector<double>> by_condition;
};

/// Band powers per window (Prediction::band_power) of a fixed vibration model; `cache` (may be
/// null) keeps a neural model's spectra between calls.
std::vector<std::vector<double>> PredictModelBands(const renderer::MaterialModel& vm,
                                                   const Replay& r,
                                                   VibrationSpectra* cache = nullptr);

/// Mean per-window E_s (as Errors::vibration) in one speed x force cell of the windows of a
/// split: where in the condition space the vibration model fails.
struct EsCell {
  double speed_lo_mps = 0, speed_hi_mps = 0, force_lo_N = 0, force_hi_N = 0;
  int n = 0;          ///< windows
  double es = 0;      ///< mean E_s [1]
  std::string label;  ///< "30-60 mm/s, 0.5-1 N"
};
/// Cells with windows, speed-major. Speed edges 10, 30, 60, 100, 150 mm/s and above; force
/// edges 0, 0.5, 1, 1.5, 2, 3 N and above. Empty when `p` has no band powers.
std::vector<EsCell> VibrationEsByCondition(const Replay& r, const Prediction& p, Split split);

}  // namespace hapticlab::modeling::wb
