#pragma once
// hapticlab rig check --clock real: the loops on the real clock, timed: a resting grip (zero
// force) or, with --render MODEL, a simulated hand stroking the rendered model.

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <string>
#include <vector>

#include "hapticlab/runner/rt_thread.hpp"

namespace hapticlab::cli {

/// Touch points [m]: a CSV file (x_m,y_m,z_m per line, an optional header) or
/// "x,y,z;x,y,z;...". @throws InputError naming the file (or --points) and line.
std::vector<Eigen::Vector3d> ParseTouchPoints(const std::string& arg);

/// Adds the real-time loop options (--rt-priority, --spin-us, --lock-memory, --cpu) to a
/// command that runs the loops on the real clock.
void AddRtOptions(CLI::App* cmd, runner::RtThreadOptions& rt);

struct TimingCheckArgs {
  /// sim: a simulated grip resting out of contact; falcon-twin: the Falcon back-end over the
  /// twin, its grip at rest; falcon, dhd, openhaptics: the hardware at zero force.
  std::string device = "sim";
  std::string firmware;           ///< falcon: the firmware file
  double motor_units_per_Nm = 0;  ///< falcon: from the rig file (0: the back-end's default)
  double max_force_N = 0;         ///< falcon: from the rig file (0: the back-end's default)
  std::string actuator = "none";  ///< "none" or "audio" (PortAudio, --audio-device)
  std::string audio_device;
  /// Material model (.toml) to render while a simulated hand strokes the virtual sample on
  /// the real clock (the tick durations of that model); empty: a resting grip out of contact,
  /// so the commanded force is zero.
  std::string render;
  double seconds = 2;
  double rate_hz = 1000;  ///< force loop rate
  bool vibration = true;  ///< run the vibration loop (10 kHz)
  bool json = false;
  runner::RtThreadOptions rt;
};

/// Runs the check, prints a cyclictest-like histogram (or JSON) and the verdict. Returns the
/// exit code: 0 when the loop kept its rate with no deadline miss, 1 otherwise.
int RunTimingCheck(const TimingCheckArgs& a);

}  // namespace hapticlab::cli
