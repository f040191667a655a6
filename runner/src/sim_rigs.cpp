#include "hapticlab/runner/sim_rigs.hpp"

#include <stdexcept>

namespace hapticlab::runner {

std::unique_ptr<SimulatedRig> OpenSimulatedRig(const std::string& device, const RigFile& rf,
                                               const sim::SimDeviceModel& generic, const sim::FalconTwinOptions& twin_o) {
  if (device != "sim" && device != "falcon-twin")
    throw std::invalid_argument("no simulated rig '" + device + "' (sim, falcon-twin)");
  auto out = std::make_unique<SimulatedRig>();
  const RigFile truth = DefaultRig(device);
  out->sim = std::make_unique<sim::SimRig>(generic, std::array<Eigen::Isometry3d, 2>{truth.DeviceFromSample(0),
                                                                                     truth.DeviceFromSample(1)});
  std::string what = "sim (generic simulated device, simulated hand)";
  if (device == "falcon-twin") {
    auto link = std::make_unique<sim::FalconTwinTransport>(out->sim->hand, out->sim->clock, twin_o);
    const auto r = devices::falcon::LoadFirmware(*link, sim::FalconTwinFirmware());
    if (!r.ok) throw std::runtime_error("falcon-twin: " + r.error);
    out->sim->twin = link.get();
    devices::falcon::FalconOptions fo;
    fo.motor_units_per_Nm = rf.motor_units_per_Nm;
    if (rf.max_force_N > 0) fo.max_force_N = rf.max_force_N;
    const devices::Clock* clock = &out->sim->clock;
    out->falcon = std::make_unique<devices::falcon::FalconDevice>(std::move(link), [clock] { return clock->Now(); }, fo);
    out->sim->generic.reset();
    out->sim->device = out->falcon.get();
    what = "falcon-twin (the Falcon back-end over an emulated Falcon, simulated hand)";
  }
  HardwareRig& h = out->rig;
  h.device = out->sim->device;
  h.actuator = &out->sim->actuator;
  h.sim = out->sim.get();
  h.device_from_sample = {rf.DeviceFromSample(0), rf.DeviceFromSample(1)};
  h.calibration = rf.text;
  h.rig_file_hash = rf.sha256;
  h.description = what + "; rig " + (rf.path.empty() ? "built-in" : rf.path) + " (sha256 " + rf.sha256.substr(0, 16) + ")";
  return out;
}

}  // namespace hapticlab::runner
