#pragma once
/// @file The simulated back-ends a session opens by name: `sim` (the generic simulated
/// device) and `falcon-twin` (the real Falcon back-end over the emulated Falcon, firmware
/// loaded through the real loader), each with its simulated hand. The real back-ends are
/// opened by devices::OpenRealDevice.

#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <string>

#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/sim/falcon_twin.hpp"
#include "hapticlab/sim/sim_device.hpp"

namespace hapticlab::sim {

/// True for the names of the simulated back-ends ("sim", "falcon-twin").
bool IsSimulatedDevice(const std::string& device);

struct SimulatedDevice {
  std::unique_ptr<SimRig> sim;  ///< clock, hand, actuator; sim->device is what the engine drives
  std::unique_ptr<devices::falcon::FalconDevice> falcon;  ///< falcon-twin only
  std::string description;  ///< e.g. "sim (generic simulated device, simulated hand)"
};

/// Opens simulated back-end `device` whose samples truly lie at `true_device_from_sample`
/// (device frame, m). `falcon` sets the twin's Falcon back-end (force calibration).
/// Precondition: IsSimulatedDevice(device). @throws std::runtime_error when the twin's
/// firmware load fails.
SimulatedDevice OpenSimulatedDevice(const std::string& device,
                                    const std::array<Eigen::Isometry3d, 2>& true_device_from_sample,
                                    const devices::falcon::FalconOptions& falcon = {},
                                    const SimDeviceModel& generic = {},
                                    const FalconTwinOptions& twin = {});

}  // namespace hapticlab::sim
