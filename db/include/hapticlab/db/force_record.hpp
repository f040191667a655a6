#pragma once
/// @file The schema of a recorded force stream ("<side>_force"): one row of 16 float32 values
/// per force tick, in the order of ForceChannel. Every writer (runner::RtEngine) and reader
/// (the exports, the tests) indexes rows through this header, never by a bare number; the
/// on-disk layout is this order and these names (TrajectoryChunk::channels).
///
/// Frame: positions, velocities and forces are in the sample frame (z normal to the sample
/// surface, pointing out of it). Time: a row's time stamp is its scheduled tick time
/// (start_time_s + i / rate_hz); `late_s` is how much later the tick ran (0 on a virtual clock).

#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace hapticlab::db {

/// The columns of a force-stream row, in on-disk order.
enum class ForceChannel : std::size_t {
  kX_m,
  kY_m,
  kZ_m,  ///< stylus tip position [m]
  kVx_mps,
  kVy_mps,
  kVz_mps,  ///< stylus tip velocity [m/s]
  kFx_N,
  kFy_N,
  kFz_N,  ///< force the renderer computed, before the safety clamp [N]
  kCmdFx_N,
  kCmdFy_N,
  kCmdFz_N,    ///< force commanded to the device, after clamp and watchdog [N]
  kNormal_N,   ///< normal (contact) force between stylus and surface [N]
  kSpeed_mps,  ///< tangential speed over the surface [m/s]
  kFault,      ///< 1 when the tick was faulted and the force zeroed, else 0
  kLate_s,     ///< how late the tick ran after its scheduled time [s]
};
inline constexpr std::size_t kForceChannelCount = 16;

/// One column: its on-disk name (unit-suffixed) and what it means.
struct ChannelSpec {
  std::string_view name;
  std::string_view meaning;
};

/// The columns in ForceChannel order.
inline constexpr std::array<ChannelSpec, kForceChannelCount> kForceChannels{{
    {"x_m", "stylus tip position, x axis of the sample frame"},
    {"y_m", "stylus tip position, y axis of the sample frame"},
    {"z_m", "stylus tip position, z axis of the sample frame (normal to the sample surface)"},
    {"vx_mps", "stylus tip velocity, x axis"},
    {"vy_mps", "stylus tip velocity, y axis"},
    {"vz_mps", "stylus tip velocity, z axis"},
    {"fx_N", "force the renderer computed, x axis (before the safety clamp)"},
    {"fy_N", "force the renderer computed, y axis (before the safety clamp)"},
    {"fz_N", "force the renderer computed, z axis (before the safety clamp)"},
    {"cmd_fx_N", "force commanded to the device, x axis (after clamp and watchdog)"},
    {"cmd_fy_N", "force commanded to the device, y axis (after clamp and watchdog)"},
    {"cmd_fz_N", "force commanded to the device, z axis (after clamp and watchdog)"},
    {"normal_N", "normal (contact) force between stylus and surface"},
    {"speed_mps", "tangential speed of the stylus over the surface"},
    {"fault",
     "1 when the tick was faulted (watchdog or renderer) and the force was zeroed, else 0"},
    {"late_s", "how much later than scheduled the force tick ran (0 on a virtual clock)"},
}};

/// The column index of `c` in a row.
constexpr std::size_t Col(ForceChannel c) { return static_cast<std::size_t>(c); }

/// The channel names in order, as a stream is opened with (TrajectoryWriter::OpenStream).
inline const std::vector<std::string>& ForceChannelNames() {
  static const std::vector<std::string> kNames = [] {
    std::vector<std::string> v;
    for (const auto& c : kForceChannels) v.emplace_back(c.name);
    return v;
  }();
  return kNames;
}

/// The vibration stream ("<side>_vibration"): one column, the acceleration at the stylus.
inline constexpr ChannelSpec kVibrationChannel{
    "acc_mps2",
    "vibrotactile acceleration felt at the stylus (actuator command or simulated hand)"};

}  // namespace hapticlab::db
