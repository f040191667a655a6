// Back-end `falcon-twin`: the real Falcon back-end (devices::falcon::FalconDevice) over the
// emulated Falcon (sim::FalconTwinTransport), its firmware loaded through the real loader,
// held by the simulated hand on the engine's virtual clock. Its rig files name the Falcon.

#include <stdexcept>

#include "backends.hpp"
#include "hapticlab/devices/falcon.hpp"

namespace hapticlab::runner::backends {

RigBackend FalconTwin() {
  RigBackend b;
  b.name = "falcon-twin";
  b.kind = DeviceKind::kSimulated;
  b.help = "the real Falcon back-end over an emulated Falcon, simulated hand and observer";
  b.falcon_frame = true;
  b.rig_device = "falcon";
  b.rig_notes =
      "# Novint Falcon: device frame at the workspace centre, z away from the base, y up.\n"
      "# The grip rests near [0, 0, 0.125]; each sample must lie below it (y < 0).\n"
      "# force.motor_units_per_Nm: measure with a force gauge (docs/hardware.md).\n";
  b.rig_file_keys = {"force.motor_units_per_Nm", "force.max_force_N"};
  b.home_position_m = sim::FalconHomePosition();
  b.open = [](const RigRequest& q, const RigFile& rf, Rig* rig) {
    const RigFile truth = DefaultRig(q.device);
    auto* s = rig->parts.Keep(std::make_unique<sim::SimRig>(
        q.generic,
        std::array<Eigen::Isometry3d, 2>{truth.DeviceFromSample(0), truth.DeviceFromSample(1)}));
    const devices::Clock* clock = &s->clock;
    if (q.real_clock) clock = rig->parts.Keep(std::make_unique<devices::SteadyClock>());
    auto link = std::make_unique<sim::FalconTwinTransport>(s->hand, *clock, q.twin);
    const auto r = devices::falcon::LoadFirmware(*link, sim::FalconTwinFirmware());
    if (!r.ok) throw std::runtime_error(q.device + ": " + r.error);
    s->twin = link.get();
    devices::falcon::FalconOptions fo;
    fo.motor_units_per_Nm = rf.motor_units_per_Nm;
    if (rf.max_force_N > 0) fo.max_force_N = rf.max_force_N;
    std::function<double()> now;  // empty: the back-end's own steady clock
    if (!q.real_clock) now = [clock] { return clock->Now(); };
    auto* falcon = rig->parts.Keep(
        std::make_unique<devices::falcon::FalconDevice>(std::move(link), std::move(now), fo));
    s->generic.reset();
    s->device = falcon;
    rig->sim = s;
    rig->device = falcon;
    rig->actuator = &s->actuator;
    return std::string("falcon-twin (the Falcon back-end over an emulated Falcon, simulated hand)");
  };
  return b;
}

}  // namespace hapticlab::runner::backends
