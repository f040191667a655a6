#include "hapticlab/runner/sim_rigs.hpp"

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/sim/simulated_device.hpp"

namespace hapticlab::runner {

std::unique_ptr<SimulatedRig> OpenSimulatedRig(const std::string& device, const RigFile& rf,
                                               const sim::SimDeviceModel& generic,
                                               const sim::FalconTwinOptions& twin_o) {
  if (!sim::IsSimulatedDevice(device))
    throw InputError("<command line>", 0, "device",
                     "no simulated rig '" + device + "' (sim, falcon-twin)");
  const RigFile truth = DefaultRig(device);
  devices::falcon::FalconOptions fo;
  fo.motor_units_per_Nm = rf.motor_units_per_Nm;
  if (rf.max_force_N > 0) fo.max_force_N = rf.max_force_N;
  auto opened = sim::OpenSimulatedDevice(
      device, {truth.DeviceFromSample(0), truth.DeviceFromSample(1)}, fo, generic, twin_o);
  auto out = std::make_unique<SimulatedRig>();
  out->sim = std::move(opened.sim);
  out->falcon = std::move(opened.falcon);
  const std::string& what = opened.description;
  HardwareRig& h = out->rig;
  h.device = out->sim->device;
  h.actuator = &out->sim->actuator;
  h.sim = out->sim.get();
  h.device_from_sample = {rf.DeviceFromSample(0), rf.DeviceFromSample(1)};
  h.calibration = rf.text;
  h.rig_file_hash = rf.sha256;
  h.description = what + "; rig " + (rf.path.empty() ? "built-in" : rf.path) + " (sha256 " +
                  rf.sha256.substr(0, 16) + ")";
  return out;
}

}  // namespace hapticlab::runner
