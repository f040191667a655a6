#pragma once
// What the vendor-SDK back-ends share (dhd.cpp, openhaptics.cpp): a hardware back-end whose
// device the SDK opens, refused with a sentence in a build made without the SDK.

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/devices/factory.hpp"
#include "hapticlab/runner/open_rig.hpp"

namespace hapticlab::runner::backends {

inline RigBackend VendorBackend(
    const std::string& name, const std::string& help, bool (*built)(),
    const std::function<std::unique_ptr<devices::HapticDevice>()>& open_device) {
  RigBackend b;
  b.name = name;
  b.kind = DeviceKind::kHardware;
  b.help = help;
  b.rig_notes = "# " + name +
                ": the vendor SDK's device frame (docs/hardware.md); force.motor_units_per_Nm is\n"
                "# not used by this back-end.\n";
  b.open = [built, open_device](const RigRequest& q, const RigFile&, Rig* rig) {
    if (!built())
      throw InputError("<command line>", 0, "device",
                       "'" + q.device +
                           "' is compiled only when its vendor SDK is found at build time, and "
                           "this build has none (docs/hardware.md)");
    try {
      rig->device = rig->parts.Keep(open_device());
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(devices::DeviceErrorMessage(q.device, e.what(), false));
    }
    return rig->device->Capabilities().name;
  };
  return b;
}

}  // namespace hapticlab::runner::backends
