#pragma once
// hapticlab rig check --clock real: the loops on the real clock, timed: a resting grip (zero
// force) or, with --render MODEL, a simulated hand stroking the rendered model.

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "hapticlab/runner/open_rig.hpp"
#include "hapticlab/runner/rt_thread.hpp"

namespace hapticlab::cli {

/// A rig's two sample poses (`--side`): the value is the pose's index.
enum class SampleSide { kLeft = 0, kRight = 1 };
inline constexpr EnumTable<SampleSide, 2> kSampleSideNames{
    {{SampleSide::kLeft, "left"}, {SampleSide::kRight, "right"}}};

/// Touch points [m]: a CSV file (x_m,y_m,z_m per line, an optional header) or
/// "x,y,z;x,y,z;...". @throws InputError naming the file (or --points) and line.
std::vector<Eigen::Vector3d> ParseTouchPoints(const std::string& arg);

/// Prints `text` (a rig file), or with `out` writes it there and says so on stderr.
void PrintOrWrite(const std::string& text, const std::string& out);

/// --device's help: `what`, then each registered back-end with its help phrase.
std::string DeviceHelp(const std::string& what);
/// The device `rig check` checks by default: the first simulated back-end that emulates a
/// hardware back-end (its code runs over an emulated device), else the default back-end.
std::string DefaultCheckDevice();

/// Adds the real-time loop options (--rt-priority, --spin-us, --lock-memory, --cpu) to a
/// command that runs the loops on the real clock.
void AddRtOptions(CLI::App* cmd, runner::RtThreadOptions& rt);

struct TimingCheckArgs {
  /// A simulated back-end on the steady clock (the generic device: a grip resting out of
  /// contact; a twin: its grip at rest), or hardware at zero force.
  std::string device = runner::DefaultBackendName();
  std::string firmware;                     ///< a back-end that needs firmware: the file
  std::optional<runner::RigFile> rig_file;  ///< --rig (force calibration); none: built-in
  /// The vibrotactile actuator (audio: PortAudio, --audio-device).
  runner::ActuatorKind actuator = runner::ActuatorKind::kNone;
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
