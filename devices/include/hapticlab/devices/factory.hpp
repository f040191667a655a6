#pragma once
/// @file The device factory: the real back-ends a session opens by name (the simulated ones,
/// `sim` and `falcon-twin`, are made by sim::OpenSimulatedDevice). Errors follow the project's
/// policy: a request that cannot name a usable device is an InputError on "<command line>"
/// whose field is the DeviceRequest member at fault; hardware that is absent or fails is a
/// std::runtime_error naming the device.

#include <functional>
#include <memory>
#include <string>

#include "hapticlab/devices/audio.hpp"
#include "hapticlab/devices/device.hpp"

namespace hapticlab::devices {
namespace falcon {
class UsbTransport;
}

/// What a session asks of the real hardware.
struct DeviceRequest {
  std::string device;             ///< "falcon", "dhd" or "openhaptics"
  std::string firmware;           ///< falcon: the firmware file (required)
  double motor_units_per_Nm = 0;  ///< falcon: from the rig file (0: the back-end's default)
  double max_force_N = 0;         ///< falcon: from the rig file (0: the back-end's default)
};

/// The one message every command gives when a device cannot be reached or started: what
/// failed (`what`, prefixed with the device's name unless it already is), then what to check
/// on the day (the cable, the power supply, the udev rule, and for the Falcon its firmware
/// file; docs/hardware.md).
std::string DeviceErrorMessage(const std::string& device, const std::string& what);

/// The Falcon's USB link (the first Falcon on the bus), with DeviceErrorMessage's sentence
/// when it is absent or cannot be claimed. @throws std::runtime_error
std::unique_ptr<falcon::UsbTransport> OpenFalconLink();

/// True for the names of the real back-ends ("falcon", "dhd", "openhaptics").
bool IsRealDevice(const std::string& device);

/// An opened haptic device and how it is described in the session's provenance.
struct OpenedDevice {
  std::unique_ptr<HapticDevice> device;
  std::string description;  ///< e.g. "falcon, firmware fw.bin"
};

/// Opens the device a request names. `progress` hears what a slow step is doing (the
/// Falcon's firmware load). @throws InputError (fields "device", "firmware") for a back-end
/// this build lacks or a missing firmware file; std::runtime_error when the device is absent
/// or its firmware does not start.
OpenedDevice OpenRealDevice(const DeviceRequest& r,
                            const std::function<void(const std::string&)>& progress = {});

/// The PortAudio actuator and masking noise, started, with the masking noise off (a session
/// turns it on while its protocol asks for it). @throws std::runtime_error when the sound
/// device cannot be opened; InputError (ValidateAudioConfig) for a bad configuration.
std::unique_ptr<AudioOutput> OpenAudioActuator(const std::string& audio_device,
                                               double full_scale_mps2);

/// The HID rating box at `vid_pid` ("VID:PID" in hex) with the report layout in
/// `layout_file`. @throws InputError (fields "rating_box", "rating_layout") for a malformed
/// id or a missing layout; std::runtime_error when the box is absent.
std::unique_ptr<RatingInput> OpenRatingBox(const std::string& vid_pid,
                                           const std::string& layout_file);

}  // namespace hapticlab::devices
