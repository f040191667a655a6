#pragma once
// What a WAV/FLAC recording cannot say, given on the command line (the defaults a sidecar
// NAME.toml overrides, docs/formats.md), and the vibration-only form of `measurement check`.

#include <CLI/CLI.hpp>
#include <limits>
#include <string>
#include <vector>

#include "hapticlab/modeling/vibration_recording.hpp"

namespace hapticlab::cli {

struct SoundFlags {
  double speed_mps = std::numeric_limits<double>::quiet_NaN();
  double force_N = std::numeric_limits<double>::quiet_NaN();
  bool unlabelled = false;
  double scale_mps2 = std::numeric_limits<double>::quiet_NaN();
  bool uncalibrated = false;
  std::string axes;
};

/// --speed, --force, --unlabelled, --scale, --uncalibrated, --axes.
void AddSoundFlags(CLI::App* cmd, SoundFlags& f);
/// The labels the flags give. @throws InputError ("<command line>", the flag) when they
/// contradict each other or a number is out of range.
modeling::SoundLabels Labels(const SoundFlags& f);

/// The words for a recording set's units in outputs: "" when all are in m/s^2, otherwise
/// " (uncalibrated: acceleration in the recordings' own units)".
std::string CalibrationNote(bool calibrated);

/// `measurement check` of a sound file or a vibration-only CSV (no kinematics): format,
/// samples, rate, axes, condition, calibration, level. Returns the exit code.
int CheckVibrationOnly(const std::string& file, const modeling::SoundLabels& labels, bool json);

}  // namespace hapticlab::cli
