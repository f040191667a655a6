// Back-end `dhd`: Force Dimension devices through the DHD API (devices/src/dhd.cpp), compiled
// only where the SDK is found at build time.

#include "backends.hpp"
#include "hapticlab/devices/vendor.hpp"
#include "vendor.hpp"

namespace hapticlab::runner::backends {

RigBackend Dhd() {
  return VendorBackend("dhd",
                       "Force Dimension devices through the DHD SDK; only in builds made with it",
                       devices::HaveDhd, [] { return devices::OpenDhd(); });
}

}  // namespace hapticlab::runner::backends
