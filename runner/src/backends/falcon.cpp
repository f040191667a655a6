// Back-end `falcon`: the Novint Falcon over libusb (devices::falcon::FalconDevice), its
// firmware loaded from the file the lab supplies; force calibration from the rig file.

#include "hapticlab/devices/falcon.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "backends.hpp"
#include "hapticlab/devices/factory.hpp"

namespace hapticlab::runner::backends {

RigBackend Falcon() {
  RigBackend b;
  b.name = "falcon";
  b.kind = DeviceKind::kHardware;
  b.help = "Novint Falcon over libusb; needs --firmware";
  b.falcon_frame = true;
  b.rig_notes =
      "# Novint Falcon: device frame at the workspace centre, z away from the base, y up.\n"
      "# The grip rests near [0, 0, 0.125]; each sample must lie below it (y < 0).\n"
      "# force.motor_units_per_Nm: measure with a force gauge (docs/hardware.md).\n";
  b.rig_file_keys = {"force.motor_units_per_Nm", "force.max_force_N"};
  b.needs_firmware = true;
  b.home_position_m = sim::FalconHomePosition();
  b.open = [](const RigRequest& q, const RigFile& rf, Rig* rig) {
    const auto fw = devices::falcon::ReadFirmwareFile(q.firmware);
    auto usb = devices::OpenFalconLink();
    if (q.progress)
      q.progress(
          fmt::format("{}: loading firmware {} ({} bytes)...", q.device, q.firmware, fw.size()));
    const auto loaded = devices::falcon::LoadFirmware(*usb, fw);
    if (!loaded.ok)
      throw std::runtime_error(devices::DeviceErrorMessage(q.device, loaded.error, true));
    if (q.progress)
      q.progress(fmt::format("{}: firmware running (attempt {})", q.device, loaded.attempts));
    devices::falcon::FalconOptions fo;
    if (rf.motor_units_per_Nm > 0) fo.motor_units_per_Nm = rf.motor_units_per_Nm;
    if (rf.max_force_N > 0) fo.max_force_N = rf.max_force_N;
    rig->device = rig->parts.Keep(std::make_unique<devices::falcon::FalconDevice>(
        std::move(usb), std::function<double()>{}, fo));
    return q.device + ", firmware " + q.firmware;
  };
  return b;
}

}  // namespace hapticlab::runner::backends
