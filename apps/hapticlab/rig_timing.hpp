#pragma once
// hapticlab rig check --clock real: the loops on the real clock, timed: a resting grip (zero
// force) or, with --render MODEL, a simulated hand stroking the rendered model.

#include <CLI/CLI.hpp>
#include <string>

#include "hapticlab/runner/rt_thread.hpp"

namespace hapticlab::cli {

/// Adds the real-time loop options (--rt-priority, --spin-us, --lock-memory, --cpu) to a
/// command that runs the loops on the real clock.
void AddRtOptions(CLI::App* cmd, runner::RtThreadOptions& rt);

struct TimingCheckArgs {
  std::string device = "sim";     ///< only "sim": a simulated grip resting out of contact
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
