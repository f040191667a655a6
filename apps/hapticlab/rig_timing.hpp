#pragma once
// hapticlab rig check --clock real: the loops on the real clock with a resting device, timed.

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
  double seconds = 2;
  double rate_hz = 1000;          ///< force loop rate
  bool vibration = true;          ///< run the vibration loop (10 kHz)
  bool json = false;
  runner::RtThreadOptions rt;
};

/// Runs the check, prints a cyclictest-like histogram (or JSON) and the verdict. Returns the
/// exit code: 0 when the loop kept its rate with no deadline miss, 1 otherwise.
int RunTimingCheck(const TimingCheckArgs& a);

}  // namespace hapticlab::cli
