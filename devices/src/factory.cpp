#include "hapticlab/devices/factory.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/devices/hid_rating.hpp"
#include "hapticlab/devices/vendor.hpp"

namespace hapticlab::devices {
namespace {

constexpr const char* kCommandLine = "<command line>";

std::unique_ptr<HapticDevice> OpenFalcon(const DeviceRequest& r,
                                         const std::function<void(const std::string&)>& progress) {
  if (r.firmware.empty())
    throw InputError(kCommandLine, 0, "firmware",
                     "the Falcon needs its firmware file (docs/hardware.md)");
  const auto fw = falcon::ReadFirmwareFile(r.firmware);
  auto usb = OpenFalconLink();
  if (progress)
    progress(fmt::format("falcon: loading firmware {} ({} bytes)...", r.firmware, fw.size()));
  const auto loaded = falcon::LoadFirmware(*usb, fw);
  if (!loaded.ok) throw std::runtime_error(DeviceErrorMessage("falcon", loaded.error));
  if (progress) progress(fmt::format("falcon: firmware running (attempt {})", loaded.attempts));
  falcon::FalconOptions fo;
  if (r.motor_units_per_Nm > 0) fo.motor_units_per_Nm = r.motor_units_per_Nm;
  if (r.max_force_N > 0) fo.max_force_N = r.max_force_N;
  return std::make_unique<falcon::FalconDevice>(std::move(usb), std::function<double()>{}, fo);
}

}  // namespace

std::string DeviceErrorMessage(const std::string& device, const std::string& what) {
  const bool named = what.rfind(device + ":", 0) == 0;
  const std::string checks =
      device == "falcon" ? "the cable, the power supply, the udev rule and the firmware file"
                         : "the cable, the power supply, the udev rule and the vendor's "
                           "driver";
  return fmt::format("{}{}; check {} (docs/hardware.md)", named ? "" : device + ": ", what, checks);
}

std::unique_ptr<falcon::UsbTransport> OpenFalconLink() {
  if (falcon::CountDevices() == 0)
    throw std::runtime_error(DeviceErrorMessage(
        "falcon", "no Novint Falcon on the USB bus (vendor 0x0403, product 0xcb48)"));
  try {
    return falcon::OpenLibusb(0);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(DeviceErrorMessage("falcon", e.what()));
  }
}

bool IsRealDevice(const std::string& device) {
  return device == "falcon" || device == "dhd" || device == "openhaptics";
}

OpenedDevice OpenRealDevice(const DeviceRequest& r,
                            const std::function<void(const std::string&)>& progress) {
  if (!IsRealDevice(r.device))
    throw InputError(kCommandLine, 0, "device",
                     "no real device '" + r.device +
                         "' (falcon, dhd, openhaptics; sim and falcon-twin are simulated)");
  if ((r.device == "dhd" && !HaveDhd()) || (r.device == "openhaptics" && !HaveOpenHaptics()))
    throw InputError(kCommandLine, 0, "device",
                     "'" + r.device +
                         "' is compiled only when its vendor SDK is found at build time, and this "
                         "build has none (docs/hardware.md)");
  OpenedDevice out;
  if (r.device == "falcon") {
    out.device = OpenFalcon(r, progress);
    out.description = "falcon, firmware " + r.firmware;
  } else {
    try {
      out.device = r.device == "dhd" ? OpenDhd() : OpenOpenHaptics();
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(DeviceErrorMessage(r.device, e.what()));
    }
    out.description = out.device->Capabilities().name;
  }
  return out;
}

std::unique_ptr<AudioOutput> OpenAudioActuator(const std::string& audio_device,
                                               double full_scale_mps2) {
  AudioConfig c;
  c.device = audio_device;
  c.full_scale_mps2 = full_scale_mps2;
  c.noise_rms_fs = 0;  // on only while the protocol asks for it
  auto audio = std::make_unique<AudioOutput>(c, OpenPortAudio());
  audio->Start();
  return audio;
}

std::unique_ptr<RatingInput> OpenRatingBox(const std::string& vid_pid,
                                           const std::string& layout_file) {
  unsigned vid = 0, pid = 0;
  char tail = 0;
  if (std::sscanf(vid_pid.c_str(), "%x:%x%c", &vid, &pid, &tail) != 2 || vid > 0xFFFF ||
      pid > 0xFFFF)
    throw InputError(kCommandLine, 0, "rating_box",
                     "expected VID:PID in hex (e.g. 046d:c216), got '" + vid_pid + "'");
  if (layout_file.empty())
    throw InputError(kCommandLine, 0, "rating_layout",
                     "the rating box needs its report layout file");
  return OpenHidRating(static_cast<std::uint16_t>(vid), static_cast<std::uint16_t>(pid),
                       LoadHidLayout(layout_file));
}

}  // namespace hapticlab::devices
