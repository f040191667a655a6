// Back-end `openhaptics`: 3D Systems (SensAble) devices through the OpenHaptics HD API
// (devices/src/openhaptics.cpp), compiled only where the SDK is found at build time.

#include "backends.hpp"
#include "hapticlab/devices/vendor.hpp"
#include "vendor.hpp"

namespace hapticlab::runner::backends {

RigBackend OpenHaptics() {
  return VendorBackend("openhaptics",
                       "3D Systems devices through OpenHaptics; only in builds made with it",
                       devices::HaveOpenHaptics, [] { return devices::OpenOpenHaptics(); });
}

}  // namespace hapticlab::runner::backends
