// Back-end `sim`: the generic simulated device (sim::SimDevice) held by the simulated hand,
// on the engine's virtual clock. The samples truly lie where the built-in rig puts them; the
// engine uses the rig file's poses (a wrong rig file touches nothing, as on a real rig).

#include "backends.hpp"

namespace hapticlab::runner::backends {

RigBackend Sim() {
  RigBackend b;
  b.name = "sim";
  b.kind = DeviceKind::kSimulated;
  b.help = "a simulated hand on a generic simulated device, rated by the simulated observer";
  b.rig_notes = "# sim: the generic simulated device, z up; samples flat at x = -3 cm and +3 cm.\n";
  b.open = [](const RigRequest& q, const RigFile&, Rig* rig) {
    const RigFile truth = DefaultRig(q.device);
    auto* s = rig->parts.Keep(std::make_unique<sim::SimRig>(
        q.generic,
        std::array<Eigen::Isometry3d, 2>{truth.DeviceFromSample(0), truth.DeviceFromSample(1)}));
    if (q.real_clock) {
      s->generic = std::make_unique<sim::SimDevice>(q.generic, s->hand, nullptr);
      s->device = s->generic.get();
    }
    rig->sim = s;
    rig->device = s->device;
    rig->actuator = &s->actuator;
    return std::string("sim (generic simulated device, simulated hand)");
  };
  return b;
}

}  // namespace hapticlab::runner::backends
