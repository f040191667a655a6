#pragma once
/// @file Back-ends on vendor SDKs that are not Debian packages, compiled only when CMake finds
/// the SDK (HL_HAVE_DHD, HL_HAVE_OPENHAPTICS): Force Dimension devices through the DHD API and
/// 3D Systems (SensAble) devices through the OpenHaptics HD API. They are written against the
/// SDKs' documented APIs; this project's CI has neither SDK, so they are compiled and tested
/// only where a lab has it (docs/hardware.md).

#include <memory>
#include <string>

#include "hapticlab/devices/device.hpp"

namespace hapticlab::devices {

/// True when this build has the back-end.
bool HaveDhd();
bool HaveOpenHaptics();

/// The first Force Dimension device (dhdOpen). @throws std::runtime_error with the SDK's message.
std::unique_ptr<HapticDevice> OpenDhd();
/// An OpenHaptics device by name ("Default Device" if empty). The HD scheduler runs its own
/// 1 kHz servo loop; state and force cross to the engine's loop through lock-free buffers.
std::unique_ptr<HapticDevice> OpenOpenHaptics(const std::string& name = "");

}  // namespace hapticlab::devices
