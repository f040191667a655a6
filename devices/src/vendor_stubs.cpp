// The vendor back-ends' entry points when their SDKs were not found at build time: they say
// so (this file is compiled instead of dhd.cpp / openhaptics.cpp).
#include <stdexcept>

#include "hapticlab/devices/vendor.hpp"

namespace hapticlab::devices {

#ifndef HL_HAVE_DHD
bool HaveDhd() { return false; }
std::unique_ptr<HapticDevice> OpenDhd() {
  throw std::runtime_error(
      "this build has no Force Dimension back-end: the DHD SDK was not found by CMake "
      "(set DHD_SDK to its folder and rebuild; docs/hardware.md)");
}
#endif
#ifndef HL_HAVE_OPENHAPTICS
bool HaveOpenHaptics() { return false; }
std::unique_ptr<HapticDevice> OpenOpenHaptics(const std::string&) {
  throw std::runtime_error(
      "this build has no OpenHaptics back-end: the OpenHaptics SDK was not found by CMake "
      "(set OH_SDK_BASE to its folder and rebuild; docs/hardware.md)");
}
#endif

}  // namespace hapticlab::devices
