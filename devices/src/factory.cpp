#include "hapticlab/devices/factory.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/devices/hid_rating.hpp"

namespace hapticlab::devices {
namespace {

constexpr const char* kCommandLine = "<command line>";
constexpr const char* kFalcon = falcon::kDeviceName;

}  // namespace

std::string DeviceErrorMessage(const std::string& device, const std::string& what,
                               bool loads_firmware) {
  const bool named = what.rfind(device + ":", 0) == 0;
  const std::string checks =
      loads_firmware ? "the cable, the power supply, the udev rule and the firmware file"
                     : "the cable, the power supply, the udev rule and the vendor's "
                       "driver";
  return fmt::format("{}{}; check {} (docs/hardware.md)", named ? "" : device + ": ", what, checks);
}

std::unique_ptr<falcon::UsbTransport> OpenFalconLink() {
  if (falcon::CountDevices() == 0)
    throw std::runtime_error(DeviceErrorMessage(
        kFalcon, "no Novint Falcon on the USB bus (vendor 0x0403, product 0xcb48)", true));
  try {
    return falcon::OpenLibusb(0);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(DeviceErrorMessage(kFalcon, e.what(), true));
  }
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
