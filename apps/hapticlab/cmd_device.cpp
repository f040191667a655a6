// hapticlab device: what hardware this machine sees, and a Falcon firmware check.

#include <fmt/format.h>
#include <hidapi/hidapi.h>

#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/devices/audio.hpp"
#include "hapticlab/devices/factory.hpp"
#include "hapticlab/devices/falcon.hpp"

namespace hapticlab::cli {

void RegisterDevice(CLI::App& app) {
  auto* grp = app.add_subcommand("device", "List and check the lab's hardware (docs/hardware.md)");
  grp->require_subcommand(1);
  {
    auto json = std::make_shared<bool>(false);
    auto* cmd = grp->add_subcommand(
        "list", "Falcons on the USB bus, audio outputs (PortAudio), HID devices (rating boxes)");
    cmd->add_flag("--json", *json, "As JSON");
    cmd->callback([json] {
      RunGuarded([&] {
        nlohmann::json j;
        j["falcons"] = devices::falcon::CountDevices();
        try {
          j["audio_outputs"] = devices::ListAudioDevices();
        } catch (const std::exception& e) {
          j["audio_outputs"] = nlohmann::json::array();
          j["audio_error"] = e.what();
        }
        nlohmann::json hids = nlohmann::json::array();
        if (hid_init() == 0) {
          hid_device_info* list = hid_enumerate(0, 0);
          for (auto* d = list; d; d = d->next) {
            std::string product;
            if (d->product_string)
              for (const wchar_t* c = d->product_string; *c; ++c)
                product += static_cast<char>(*c < 128 ? *c : '?');
            hids.push_back(fmt::format("{:04x}:{:04x} {}", d->vendor_id, d->product_id, product));
          }
          hid_free_enumeration(list);
          hid_exit();
        }
        j["hid"] = hids;
        if (*json) {
          PrintJson(j);
        } else {
          fmt::print("Novint Falcons: {}\n", j["falcons"].get<int>());
          fmt::print("audio outputs:{}\n", j["audio_outputs"].empty() ? " none" : "");
          for (const auto& a : j["audio_outputs"]) fmt::print("  {}\n", a.get<std::string>());
          fmt::print("HID devices:{}\n", hids.empty() ? " none" : "");
          for (const auto& h : hids) fmt::print("  {}\n", h.get<std::string>());
        }
        return kExitOk;
      });
    });
  }
  {
    auto fw = std::make_shared<std::string>();
    auto* cmd = grp->add_subcommand(
        "falcon-load", "Load the Falcon's firmware and report each step (to check a rig)");
    cmd->add_option("--firmware", *fw, "Firmware file (yours)")->required();
    cmd->callback([fw] {
      RunGuarded({{"firmware", "--firmware"}}, [&] {
        const auto bytes = devices::falcon::ReadFirmwareFile(*fw);
        auto usb = devices::OpenFalconLink();
        const auto r = devices::falcon::LoadFirmware(*usb, bytes);
        std::string trace;
        for (const auto s : r.trace)
          trace +=
              fmt::format("{}{}", trace.empty() ? "" : " -> ", devices::falcon::LoadStateName(s));
        fmt::print("{} after {} attempt(s): {}\n", r.ok ? "loaded" : "FAILED", r.attempts, trace);
        if (!r.ok)
          fmt::print("{}\n",
                     devices::DeviceErrorMessage(devices::falcon::kDeviceName, r.error, true));
        return r.ok ? kExitOk : kExitFailure;
      });
    });
  }
}

}  // namespace hapticlab::cli
