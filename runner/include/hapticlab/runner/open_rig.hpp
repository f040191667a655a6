#pragma once
/// @file One rig, opened from one registry. A `Rig` is everything a session drives: the haptic
/// device, the vibrotactile actuator, the masking noise, the rating input, the sample poses of
/// the rig file and, on a simulated back-end, the simulation behind the device (the simulated
/// hand and its clock). `OpenRig` opens one by back-end name from the registry of back-ends
/// (`RigBackend`: name -> factory, capabilities, the rig-file keys it reads). The built-in
/// back-ends are `sim`, `falcon-twin`, `falcon`, `dhd` and `openhaptics`, each in its own
/// file under runner/src/backends/ and one line in the registry's list
/// (runner/src/backend_registry.cpp); a program may register more (`RegisterBackend`).
/// docs/hardware.md, "Adding a device back-end".

#include <Eigen/Geometry>
#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hapticlab/core/enum_names.hpp"
#include "hapticlab/devices/device.hpp"
#include "hapticlab/runner/rig.hpp"
#include "hapticlab/sim/falcon_twin.hpp"
#include "hapticlab/sim/sim_device.hpp"

namespace hapticlab::runner {

/// What a back-end's device is: simulated (a simulated hand holds it; the simulated observer
/// rates unless a participant window does) or hardware (a person holds it and rates).
enum class DeviceKind { kSimulated, kHardware };

/// The vibrotactile actuator a rig plays the vibration on (`--actuator`; recorded as the
/// session's `actuator`): none, or the sound card (PortAudio) with masking noise.
enum class ActuatorKind { kNone, kAudio };
inline constexpr EnumTable<ActuatorKind, 2> kActuatorNames{
    {{ActuatorKind::kNone, "none"}, {ActuatorKind::kAudio, "audio"}}};

/// The parts a rig owns, released in the reverse order they were kept (a device may borrow
/// what was kept before it: the Falcon twin's link borrows the simulated hand).
class RigParts {
 public:
  RigParts() = default;
  RigParts(const RigParts&) = delete;
  RigParts& operator=(const RigParts&) = delete;
  RigParts(RigParts&&) = default;
  RigParts& operator=(RigParts&&) = default;
  ~RigParts() {
    while (!parts_.empty()) parts_.pop_back();
  }
  /// Keeps `part` alive as long as the rig; returns it.
  template <typename T>
  T* Keep(std::unique_ptr<T> part) {
    T* raw = part.get();
    parts_.push_back(std::shared_ptr<T>(std::move(part)));
    return raw;
  }

 private:
  std::vector<std::shared_ptr<void>> parts_;
};

struct RigBackend;

/// The rig a session runs on (RunOptions::rig, borrowed): opened by OpenRig, or assembled by
/// a caller from devices it owns (tests).
struct Rig {
  devices::HapticDevice* device = nullptr;  ///< required
  devices::Actuator* actuator = nullptr;  ///< the vibrotactile actuator (may be null: no vibration)
  devices::MaskingNoise* noise = nullptr;  ///< headphones (may be null)
  double noise_rms_fs = 0.1;               ///< masking level when the protocol asks for noise
  /// Pose of each sample (0 left, 1 right) in the device frame: origin on the sample's base
  /// plane, +z out of the sample (the rig file's; docs/hardware.md).
  std::array<Eigen::Isometry3d, 2> device_from_sample{sim::DefaultSamplePoses()};
  std::string description;    ///< recorded in the session's provenance
  std::string calibration;    ///< recorded with the session (rig file content)
  std::string rig_file_hash;  ///< SHA-256 of the rig file (provenance), empty: none
  /// The participant's input device besides the window (a rating box; null: the window).
  devices::RatingInput* rating_input = nullptr;
  /// A simulated back-end's simulation (borrowed from `parts`): its virtual clock runs the
  /// engine, its hand explores, the observer rates. Null on hardware. Only the simulation
  /// seam (runner/src/simulation.cpp) reads it; the trial code never does.
  sim::SimRig* sim = nullptr;
  const RigBackend* backend = nullptr;  ///< what opened it (null: assembled by the caller)
  RigParts parts;                       ///< what the rig owns
};

/// What a session (or a rig command) asks of a back-end.
struct RigRequest {
  std::string device;               ///< a registered back-end's name
  std::optional<RigFile> rig_file;  ///< frames and calibration; none: the back-end's built-in rig
  std::string firmware;             ///< a back-end that needs_firmware: its firmware file
  ActuatorKind actuator = ActuatorKind::kNone;
  std::string audio_device;     ///< PortAudio output device (name substring; empty: default)
  double full_scale_mps2 = 50;  ///< acceleration at the sound card's full scale
  double noise_rms_fs = 0.1;    ///< masking level when the protocol asks for noise
  std::string rating_box;       ///< "VID:PID" of a HID rating box (empty: none)
  std::string rating_layout;    ///< the box's report layout file
  sim::SimDeviceModel generic;  ///< simulated back-ends: the generic device's model
  sim::FalconTwinOptions twin;  ///< the Falcon twin's emulated link
  /// Simulated back-ends: the device and the hand on the steady clock (rig check --clock
  /// real), not on the engine's virtual clock (Rig::sim->clock then stands still).
  bool real_clock = false;
  std::function<void(const std::string&)> progress;  ///< slow steps (a firmware load)
};

/// A device back-end: its name, what it can do, the rig-file keys it reads and its factory.
struct RigBackend {
  std::string name;
  DeviceKind kind = DeviceKind::kHardware;
  std::string help;  ///< one phrase for --device's help, e.g. "Novint Falcon over libusb"
  /// The built-in rig's geometry: the Falcon's frame (y up, samples below the workspace
  /// centre) or a table (z up, samples flat at x = -+3 cm).
  bool falcon_frame = false;
  /// The device the rig files of this back-end name (a twin: the device it emulates;
  /// empty: `name`), and what `rig init` writes above a template for it.
  std::string rig_device;
  std::string rig_notes;
  /// The rig-file keys the back-end reads besides the frames (docs/hardware.md).
  std::vector<std::string> rig_file_keys;
  bool needs_firmware = false;  ///< RigRequest::firmware is required
  /// Where the grip rests before a participant takes it [m, device frame].
  Eigen::Vector3d home_position_m{0, 0, 0.05};
  /// Opens the device into `rig` (rig->device, rig->sim on a simulated back-end, the parts it
  /// owns in rig->parts) from the request and its rig file; returns how the session's
  /// provenance describes it, e.g. "falcon, firmware fw.bin". @throws InputError (field
  /// "device" or "firmware") for a request that cannot name a usable device;
  /// std::runtime_error when the device is absent or fails.
  std::function<std::string(const RigRequest&, const RigFile&, Rig*)> open;

  bool simulated() const { return kind == DeviceKind::kSimulated; }
  /// The device its rig files name (rig_device, else name).
  const std::string& RigDevice() const { return rig_device.empty() ? name : rig_device; }
};

/// Adds a back-end to the registry (a program's own, e.g. a test's toy device). Precondition:
/// no back-end of that name is registered, `open` is set.
void RegisterBackend(RigBackend backend);
/// Removes a back-end a program registered, e.g. at the end of a test's scope. Precondition: it
/// is the last one registered and not built in (registrations end in reverse order, so every
/// other back-end's address stays valid), and no Rig opened from it is alive.
void UnregisterBackend(const std::string& name);
/// Every registered back-end, the built-in ones first (registry order).
std::vector<const RigBackend*> Backends();
/// Their names, for a CLI's list of choices.
std::vector<std::string> BackendNames();
/// The back-end a session uses when none is named: the first registered (sim).
std::string DefaultBackendName();
/// The back-end `name`, or null.
const RigBackend* FindBackend(const std::string& name);
/// The back-end `name`. @throws InputError (file "<command line>", field "device") listing
/// the registered names.
const RigBackend& GetBackend(const std::string& name);
/// True when `name` is a registered simulated back-end.
bool IsSimulatedBackend(const std::string& name);
/// The simulated back-ends' names, for messages: "sim or falcon-twin".
std::string SimulatedBackendList();

/// Opens the rig a request names: the back-end's device, then the actuator and the rating
/// box. Errors: InputError on "<command line>" with the RigRequest member at fault as field
/// ("device", "firmware", "actuator": an actuator on a simulated rig, "rating_box",
/// "rating_layout"); std::runtime_error when
/// hardware is absent or fails (devices::DeviceErrorMessage's sentence).
std::unique_ptr<Rig> OpenRig(const RigRequest& request);

}  // namespace hapticlab::runner
