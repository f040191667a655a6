#include "hapticlab/sim/simulated_device.hpp"

#include <stdexcept>

#include "hapticlab/core/status.hpp"

namespace hapticlab::sim {

bool IsSimulatedDevice(const std::string& device) {
  return device == "sim" || device == "falcon-twin";
}

SimulatedDevice OpenSimulatedDevice(const std::string& device,
                                    const std::array<Eigen::Isometry3d, 2>& true_device_from_sample,
                                    const devices::falcon::FalconOptions& falcon,
                                    const SimDeviceModel& generic, const FalconTwinOptions& twin) {
  HL_REQUIRE(IsSimulatedDevice(device),
             "no simulated back-end '" + device + "' (sim, falcon-twin)");
  SimulatedDevice out;
  out.sim = std::make_unique<SimRig>(generic, true_device_from_sample);
  out.description = "sim (generic simulated device, simulated hand)";
  if (device == "falcon-twin") {
    auto link = std::make_unique<FalconTwinTransport>(out.sim->hand, out.sim->clock, twin);
    const auto r = devices::falcon::LoadFirmware(*link, FalconTwinFirmware());
    if (!r.ok) throw std::runtime_error("falcon-twin: " + r.error);
    out.sim->twin = link.get();
    const devices::Clock* clock = &out.sim->clock;
    out.falcon = std::make_unique<devices::falcon::FalconDevice>(
        std::move(link), [clock] { return clock->Now(); }, falcon);
    out.sim->generic.reset();
    out.sim->device = out.falcon.get();
    out.description = "falcon-twin (the Falcon back-end over an emulated Falcon, simulated hand)";
  }
  return out;
}

}  // namespace hapticlab::sim
