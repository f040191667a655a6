// The registry of device back-ends and OpenRig (runner/open_rig.hpp).

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <deque>
#include <mutex>

#include "backends/backends.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/devices/factory.hpp"
#include "hapticlab/runner/open_rig.hpp"

namespace hapticlab::runner {
namespace {

constexpr const char* kCommandLine = "<command line>";

// The registry: the built-in back-ends (HL_BUILT_IN_BACKENDS, runner/src/backends/backends.hpp),
// then what a program registers. A deque,
// so a back-end's address (Rig::backend) stays valid as others are added.
struct Registry {
  std::mutex m;
  std::deque<RigBackend> list;
  std::size_t built_in = 0;  ///< the first `built_in` entries
  Registry() {
#define HL_REGISTER_BACKEND(Name) list.push_back(backends::Name());
    HL_BUILT_IN_BACKENDS(HL_REGISTER_BACKEND)
#undef HL_REGISTER_BACKEND
    built_in = list.size();
  }
};

Registry& TheRegistry() {
  static Registry r;
  return r;
}

}  // namespace

void RegisterBackend(RigBackend backend) {
  HL_REQUIRE(!backend.name.empty() && backend.open, "a back-end needs a name and a factory");
  HL_REQUIRE(FindBackend(backend.name) == nullptr,
             "back-end '" + backend.name + "' is registered already");
  Registry& r = TheRegistry();
  const std::lock_guard lock(r.m);
  r.list.push_back(std::move(backend));
}

void UnregisterBackend(const std::string& name) {
  Registry& r = TheRegistry();
  const std::lock_guard lock(r.m);
  HL_REQUIRE(r.list.size() > r.built_in && r.list.back().name == name,
             "back-end '" + name + "' is not the last one a program registered");
  r.list.pop_back();  // a deque's pop_back leaves the other elements' addresses valid
}

std::vector<const RigBackend*> Backends() {
  Registry& r = TheRegistry();
  const std::lock_guard lock(r.m);
  std::vector<const RigBackend*> out;
  for (const auto& b : r.list) out.push_back(&b);
  return out;
}

std::vector<std::string> BackendNames() {
  std::vector<std::string> out;
  for (const auto* b : Backends()) out.push_back(b->name);
  return out;
}

std::string DefaultBackendName() { return Backends().front()->name; }

const RigBackend* FindBackend(const std::string& name) {
  for (const auto* b : Backends())
    if (b->name == name) return b;
  return nullptr;
}

const RigBackend& GetBackend(const std::string& name) {
  if (const auto* b = FindBackend(name)) return *b;
  throw InputError(
      kCommandLine, 0, "device",
      fmt::format("no device back-end '{}' ({})", name, fmt::join(BackendNames(), ", ")));
}

bool IsSimulatedBackend(const std::string& name) {
  const auto* b = FindBackend(name);
  return b && b->simulated();
}

std::string SimulatedBackendList() {
  std::vector<std::string> names;
  for (const auto* b : Backends())
    if (b->simulated()) names.push_back(b->name);
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return out;
}

std::unique_ptr<Rig> OpenRig(const RigRequest& q) {
  const RigBackend& b = GetBackend(q.device);
  if (b.needs_firmware && q.firmware.empty())
    throw InputError(kCommandLine, 0, "firmware",
                     "'" + b.name + "' needs its firmware file (docs/hardware.md)");
  const RigFile rf = q.rig_file ? *q.rig_file : DefaultRig(q.device);
  auto rig = std::make_unique<Rig>();
  rig->backend = &b;
  rig->device_from_sample = {rf.DeviceFromSample(0), rf.DeviceFromSample(1)};
  rig->calibration = rf.text;
  rig->rig_file_hash = rf.sha256;
  std::string what = b.open(q, rf, rig.get());
  HL_REQUIRE(rig->device != nullptr, "back-end '" + b.name + "' opened no device");
  if (b.simulated() && q.actuator != ActuatorKind::kNone)
    throw InputError(kCommandLine, 0, "actuator",
                     "a simulated rig plays vibration to the simulated hand; use --actuator none");
  if (q.actuator == ActuatorKind::kAudio) {
    auto* audio = rig->parts.Keep(devices::OpenAudioActuator(q.audio_device, q.full_scale_mps2));
    rig->actuator = audio;
    rig->noise = audio;
    rig->noise_rms_fs = q.noise_rms_fs;
    what += "; audio actuator and masking noise";
  }
  rig->description = what + "; rig " + (rf.path.empty() ? "built-in" : rf.path) + " (sha256 " +
                     rf.sha256.substr(0, 16) + ")";
  if (!q.rating_box.empty())
    rig->rating_input = rig->parts.Keep(devices::OpenRatingBox(q.rating_box, q.rating_layout));
  return rig;
}

}  // namespace hapticlab::runner
