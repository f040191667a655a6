#pragma once
/// @file Workbench replay (DESIGN.md §4): a measurement (core/measurement.hpp) prepared for
/// replaying through a model. Frames and units: positions x_m, y_m in the sample's surface frame
/// [m] (z up, out of the surface), penetration d_m = -z >= 0 [m], velocities [m/s], forces of the
/// surface on the tool [N] (f_n = +z component), direction of motion dir_rad in (-pi, pi] from +x.
/// Vibration windows hold band powers of the tool acceleration [(m/s^2)^2 per FFT bin].

#include <array>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "hapticlab/core/measurement.hpp"

namespace hapticlab::modeling::wb {

/// Friction regimes by tangential speed (Algorithm 1's T_v1 and T_v2, dissertation ch. IV.3):
/// pre-sliding at or below kPreslidingSpeed_mps, sliding at or above kSlidingSpeed_mps [m/s].
inline constexpr double kPreslidingSpeed_mps = 0.5e-3;
inline constexpr double kSlidingSpeed_mps = 3e-3;

/// A measurement prepared for replay: force samples (decimated to <= max_force_rate_hz) and
/// vibration windows, each tagged with its time block (train/held-out split).
class Replay {
 public:
  std::string file;
  double rate_hz = 0;    ///< rate of the force samples after decimation [Hz]
  double block_s = 1.0;  ///< length of a time block of the split [s]
  struct Sample {
    double t_s, x_m, y_m, d_m, ddot_mps, vx_mps, vy_mps, speed_mps, dir_rad, fn_N, ftx_N, fty_N;
    /// Measured normal force averaged over ReplayOptions::load_smoothing_s (rows in contact):
    /// the load that sets the Coulomb level. Raw sensor noise through the bristle's saturation
    /// (|F| <= f_C) would bias the friction level low, and a fitted mu_k high.
    double fload_N;
    bool contact;
    int block;
    int row;        ///< index of the measurement row
    int recording;  ///< the row's recording id (Measurement::recording_ids; 0 without)
  };
  /// The force samples in time order (read-only; built by PrepareReplay).
  const std::vector<Sample>& samples() const { return samples_; }
  /// Write access for the code that builds a replay or perturbs a copy of one (PrepareReplay,
  /// sensitivity replays, tests); everything else reads samples().
  std::vector<Sample>& mutable_samples() { return samples_; }
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;  ///< bounds of the positions in contact
  double position_resolution_m =
      1e-6;  ///< the Dahl bristle follows the tool through a play of this width [m]

  bool has_vibration = false;
  double acc_rate_hz = 0;
  std::vector<double> band_lo_hz, band_hi_hz;  ///< log-spaced analysis bands
  struct Window {
    double t_s, speed_mps, force_N;
    std::array<double, 4> dir;       ///< speed-weighted means of cos φ, sin φ, cos 2φ, sin 2φ
    std::vector<double> band_power;  ///< mean periodogram power per band [(m/s^2)^2 per bin]
    int block;
    int row0, rows;  ///< measurement rows of the window
    int recording;   ///< recording id of its first row
  };
  std::vector<Window> windows;  ///< steady windows in contact with mean speed >= 1 cm/s

 private:
  std::vector<Sample> samples_;
};

struct ReplayOptions {
  double max_force_rate_hz = 500;  ///< force samples are decimated to at most this rate
  double block_s = 1.0;            ///< split blocks: even blocks train, odd blocks held out
  double window_s = 0.128;         ///< vibration window (rounded to a power of two samples)
  int bands = 8;                   ///< log-spaced bands from 20 Hz to min(1000 Hz, 0.45 rate)
  double contact_force_N = 0.02;   ///< a sample is in contact when f_n exceeds this
  double min_speed_mps = 0.01;     ///< vibration windows below this speed are not scored
  double max_variation =
      0.35;  ///< windows whose speed or load varies more (SD / mean) are not scored
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
  /// Sample::x_m / y_m by a window chosen per sample, up to position_smoothing_s, by the
  /// intersection of confidence intervals against the position noise (long at rest, short where
  /// the tool moves fast or turns); false: position_smoothing_s everywhere.
  bool position_adaptive = true;
  std::vector<double> band_edges_hz;  ///< explicit band edges (a model's); empty: log-spaced
  /// Log-spaced bands end at or below this [Hz] (0: no limit): a fixed vibration model's own
  /// band (workbench_vibration.hpp, VibrationModelTopHz).
  double max_band_hz = 0;
};

/// Prepares a measurement (vibration windows hop by a quarter window). @throws InputError when it
/// has no samples in contact.
Replay PrepareReplay(const Measurement& m, const ReplayOptions& o = {});

/// `measurement check`: duration, rate, ranges, gaps.
struct MeasurementSummary {
  double duration_s = 0, rate_hz = 0, max_gap_s = 0;
  int samples = 0, gaps = 0, contact_samples = 0;
  std::map<std::string, std::pair<double, double>> ranges;  ///< column -> (min, max)
  std::vector<std::string> warnings;
};
MeasurementSummary Summarize(const Measurement& m);

}  // namespace hapticlab::modeling::wb
