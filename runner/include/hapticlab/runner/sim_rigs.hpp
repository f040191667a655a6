#pragma once
/// @file Simulated rigs ready for a session: `sim` (the generic simulated device) and
/// `falcon-twin` (the real Falcon back-end over the emulated Falcon, firmware loaded through
/// the real loader). The samples truly lie where the back-end's built-in rig puts them; the
/// engine uses the rig file's poses (a wrong rig file touches nothing, as on a real rig).

#include <memory>
#include <string>

#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/runner/rig.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/sim/falcon_twin.hpp"
#include "hapticlab/sim/sim_device.hpp"

namespace hapticlab::runner {

struct SimulatedRig {
  std::unique_ptr<sim::SimRig> sim;
  std::unique_ptr<devices::falcon::FalconDevice> falcon;  ///< falcon-twin only
  HardwareRig rig;  ///< what a session borrows (poses and calibration from the rig file)
};

/// @param device "sim" or "falcon-twin"
/// @throws InputError (file "<command line>", field "device") for another name;
///         std::runtime_error when the twin's firmware load fails
std::unique_ptr<SimulatedRig> OpenSimulatedRig(const std::string& device, const RigFile& rig_file,
                                               const sim::SimDeviceModel& generic = {},
                                               const sim::FalconTwinOptions& twin = {});

}  // namespace hapticlab::runner
