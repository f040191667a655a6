#pragma once
/// @file The tool's state as a haptic device reports it: the plain data shared by the device
/// back-ends (devices/), which produce it, and the renderer (renderer/), which consumes it,
/// so that neither module depends on the other for it.
///
/// Frame: the producer's. A device's Read fills it in the device frame; RtEngine transforms
/// it into the sample's frame (z the surface normal, out of the surface; renderer/force.hpp)
/// before the renderer's force tick sees it. SI units throughout.

#include <Eigen/Core>

namespace hapticlab {

/// Tool state as read from the device.
struct ToolState {
  Eigen::Vector3d p_m = Eigen::Vector3d::Zero();    ///< tool tip position [m]
  Eigen::Vector3d v_mps = Eigen::Vector3d::Zero();  ///< tool tip velocity [m/s]
};

/// Device reading handed to the force tick.
struct DeviceSample {
  ToolState state;
  double t_s = 0;  ///< time the sample was measured [s]
  /// A measured normal force (a force sensor, or a recorded trajectory's force): when
  /// present it drives the vibration model instead of the rendered normal force, and the
  /// vibration is on while it is > 0 (the Penn toolkit's rendering reads the device's force).
  bool has_normal_force = false;
  double normal_force_N = 0;
};

}  // namespace hapticlab
