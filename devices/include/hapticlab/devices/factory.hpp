#pragma once
/// @file What the device back-ends share when they open hardware (runner/open_rig.hpp opens a
/// rig by back-end name): the one device error message, the Falcon's USB link, the audio
/// actuator and the rating box. Errors follow the project's policy: a request that cannot name
/// a usable device is an InputError on "<command line>" whose field is the request's member at
/// fault; hardware that is absent or fails is a std::runtime_error naming the device.

#include <functional>
#include <memory>
#include <string>

#include "hapticlab/devices/audio.hpp"
#include "hapticlab/devices/device.hpp"

namespace hapticlab::devices {
namespace falcon {
class UsbTransport;
}

/// The one message every command gives when a device cannot be reached or started: what
/// failed (`what`, prefixed with the device's name unless it already is), then what to check
/// on the day (the cable, the power supply, the udev rule, and the firmware file for a device
/// that loads one, else the vendor's driver; docs/hardware.md).
std::string DeviceErrorMessage(const std::string& device, const std::string& what,
                               bool loads_firmware);

/// The Falcon's USB link (the first Falcon on the bus), with DeviceErrorMessage's sentence
/// when it is absent or cannot be claimed. @throws std::runtime_error
std::unique_ptr<falcon::UsbTransport> OpenFalconLink();

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
