#pragma once
/// @file Offline rendering: the real-time ticks run over a recorded trajectory, with the
/// trajectory's time stamps as the clock (for inspection and for the workbench).

#include <vector>

#include "hapticlab/core/measurement.hpp"
#include "hapticlab/renderer/hybrid.hpp"

namespace hapticlab::runner {

/// One force tick of an offline render.
struct OfflineRow {
  double t_s = 0;
  Eigen::Vector3d force_N = Eigen::Vector3d::Zero();    ///< model force before filtering
  Eigen::Vector3d command_N = Eigen::Vector3d::Zero();  ///< filtered, clamped command
  double normal_N = 0, friction_N = 0, speed_mps = 0;
  bool in_contact = false, fault = false;
  double acc_mps2 = 0;  ///< the vibration sample synthesized at the tick's time
};

struct OfflineResult {
  std::vector<OfflineRow> rows;        ///< one per trajectory sample
  std::vector<double> vibration_mps2;  ///< every vibration sample, at the vibration rate
};

struct OfflineOptions {
  /// Hand each row's fz_N (the force the surface exerts on the tool, along the normal) to the
  /// renderer as the measured normal force that drives the vibration model.
  bool measured_normal_force = false;
};

/// Runs one force tick per trajectory row (the row's t_s is both sample and tick time) and
/// as many vibration ticks as the vibration rate puts between consecutive rows.
OfflineResult RenderOffline(const renderer::MaterialModel& model,
                            const renderer::RenderOptions& options, const Measurement& trajectory,
                            const OfflineOptions& offline = {});

}  // namespace hapticlab::runner
