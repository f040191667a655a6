// hapticlab rig init / rig touch: setting a rig up by touching it. `init` writes a commented
// rig-file template for a device; `touch` streams the tool tip's position and records the
// points a person touches (Enter, or the Falcon grip's button), in the format `rig calibrate`
// reads. On a simulated device, --script plays the touches with the simulated hand.

#include <fmt/core.h>
#include <poll.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <memory>
#include <thread>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/runner/open_rig.hpp"
#include "hapticlab/runner/rig.hpp"
#include "rig_timing.hpp"

namespace hapticlab::cli {
namespace {

std::string Mm(const Eigen::Vector3d& p) {
  return fmt::format("[{:8.2f}, {:8.2f}, {:8.2f}]", p.x() * 1e3, p.y() * 1e3, p.z() * 1e3);
}

std::string RigTemplate(const std::string& device) {
  return "# Rig-file template for device '" + device + "' (hapticlab rig init).\n" +
         runner::GetBackend(device).rig_notes +
         "# Steps: 1. place the samples; 2. `hapticlab rig touch --device " + device +
         " -o left.csv`\n"
         "# (touch four spread points on the left sample, the first two along its x axis);\n"
         "# 3. `hapticlab rig calibrate THIS_FILE --side left --points left.csv --out "
         "THIS_FILE`;\n"
         "# the same for the right sample; 4. `hapticlab rig show THIS_FILE` and `rig check`.\n"
         "# The poses below are the built-in rig's: placeholders until calibrated.\n\n" +
         runner::RigToToml(runner::DefaultRig(device));
}

// Non-blocking: true when a line arrived on stdin (Enter). Sets *closed at end of input.
bool EnterPressed(bool* closed) {
  if (*closed) return false;
  pollfd p{STDIN_FILENO, POLLIN, 0};
  if (poll(&p, 1, 0) <= 0 || !(p.revents & (POLLIN | POLLHUP))) return false;
  char buf[256];
  const auto n = read(STDIN_FILENO, buf, sizeof buf);
  if (n <= 0) {
    *closed = true;
    return false;
  }
  for (ssize_t i = 0; i < n; ++i)
    if (buf[i] == '\n') return true;
  return false;
}

struct TouchArgs {
  std::string device, rig, firmware, script, out;
  SampleSide side = SampleSide::kLeft;
  int points = 4;
};

// The device a touch session reads: a simulated rig (virtual clock stepped here) or hardware.
struct TouchDevice {
  std::unique_ptr<runner::Rig> rig;
  devices::HapticDevice* dev = nullptr;
  const devices::falcon::FalconDevice* falcon = nullptr;  // the grip's buttons
  double t_s = 0;
  // One read [device frame]; false when the read carried no new sample.
  bool Read(Eigen::Vector3d* p) {
    renderer::DeviceSample s;
    if (rig->sim) {
      t_s += 1e-3;
      rig->sim->clock.Set(t_s);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    const bool ok = dev->Read(&s) == devices::ReadResult::kOk;
    dev->WriteForce(Eigen::Vector3d::Zero());
    if (ok) *p = s.state.p_m;
    return ok;
  }
};

TouchDevice OpenTouchDevice(const TouchArgs& a, const runner::RigFile& rf) {
  TouchDevice d;
  if (!runner::GetBackend(a.device).simulated() && !a.script.empty())
    throw InputError(
        kCommandLine, 0, "--script",
        "scripted touches drive a simulated hand: --device " + runner::SimulatedBackendList());
  runner::RigRequest q{.device = a.device, .rig_file = rf, .firmware = a.firmware};
  q.progress = [](const std::string& s) { fmt::print(stderr, "{}\n", s); };
  WithFlags({{"device", "--device"}, {"firmware", "--firmware"}},
            [&] { d.rig = runner::OpenRig(q); });
  d.dev = d.rig->device;
  if (d.rig->sim && d.rig->sim->twin) d.rig->sim->twin->BeginRun();
  if (!d.rig->sim) d.dev->SetTimeBase(std::chrono::steady_clock::now());
  d.falcon = dynamic_cast<const devices::falcon::FalconDevice*>(d.dev);
  return d;
}

int RunTouch(const TouchArgs& a) {
  const bool have_rig = !a.rig.empty();
  const auto rf = have_rig ? runner::LoadRig(a.rig)
                           : runner::DefaultRig(runner::GetBackend(a.device).RigDevice());
  const int side = static_cast<int>(a.side);
  std::vector<Eigen::Vector3d> script;
  if (!a.script.empty()) script = ParseTouchPoints(a.script);
  const int wanted = script.empty() ? a.points : static_cast<int>(script.size());
  TouchDevice d = OpenTouchDevice(a, rf);
  const Eigen::Isometry3d sample_from_device = rf.DeviceFromSample(side).inverse();
  fmt::print(stderr, "{}: touch {} points on the {} sample; {} records each\n", a.device, wanted,
             NameOf(kSampleSideNames, a.side),
             !script.empty() ? "the script"
             : d.falcon      ? "Enter or a grip button"
                             : "Enter");
  constexpr int kMean = 20;  // a recorded point: the mean of the last 20 reads (20 ms)
  std::array<Eigen::Vector3d, kMean> ring;
  int filled = 0, since_print = 0;
  std::uint8_t buttons_before = 0;
  bool stdin_closed = false;
  std::vector<Eigen::Vector3d> pts;
  std::size_t reads_held = 0;
  if (!script.empty()) d.rig->sim->hand.Hold(d.rig->sim->true_device_from_sample[side], script[0]);
  while (static_cast<int>(pts.size()) < wanted) {
    Eigen::Vector3d p;
    if (!d.Read(&p)) continue;
    ring[static_cast<std::size_t>(filled % kMean)] = p;
    ++filled;
    ++reads_held;
    bool record = false;
    if (!script.empty()) {
      record = reads_held >= 100 && filled >= kMean;  // held still for 100 ms
    } else {
      const std::uint8_t b = d.falcon ? d.falcon->last_status().buttons : 0;
      record = (b & ~buttons_before) != 0 || EnterPressed(&stdin_closed);
      buttons_before = b;
      if (stdin_closed && !d.falcon)
        throw std::runtime_error(fmt::format(
            "standard input closed after {} of {} touches (press Enter to record a touch)",
            pts.size(), wanted));
      if (++since_print >= 100) {  // 10 lines a second
        since_print = 0;
        fmt::print(stderr, "tip {} mm device{}\n", Mm(p),
                   have_rig ? fmt::format(", {} mm {} sample", Mm(sample_from_device * p),
                                          NameOf(kSampleSideNames, a.side))
                            : "");
      }
    }
    if (!record || filled < kMean) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& q : ring) mean += q / kMean;
    pts.push_back(mean);
    fmt::print(stderr, "point {}: {} mm device{}\n", pts.size(), Mm(mean),
               have_rig ? fmt::format(", {} mm {} sample", Mm(sample_from_device * mean),
                                      NameOf(kSampleSideNames, a.side))
                        : "");
    filled = 0;
    reads_held = 0;
    if (!script.empty() && pts.size() < script.size())
      d.rig->sim->hand.Hold(d.rig->sim->true_device_from_sample[side], script[pts.size()]);
  }
  std::string csv = "x_m,y_m,z_m\n";
  for (const auto& q : pts) csv += fmt::format("{:.9g},{:.9g},{:.9g}\n", q.x(), q.y(), q.z());
  if (a.out.empty()) {
    fmt::print("{}", csv);
  } else {
    WriteTextFile(a.out, csv);
    fmt::print(stderr,
               "wrote {} ({} points, device frame; `hapticlab rig calibrate RIG --side {} "
               "--points {}`)\n",
               a.out, pts.size(), NameOf(kSampleSideNames, a.side), a.out);
  }
  return kExitOk;
}

}  // namespace

void RegisterRigSetup(CLI::App& rig) {
  {
    struct O {
      std::string device, out;
    };
    auto o = std::make_shared<O>();
    auto* cmd = rig.add_subcommand(
        "init", "Write a commented rig-file template for a device (read back by `rig show`)");
    cmd->add_option("--device", o->device, "The device the rig uses")
        ->check(CLI::IsMember(runner::BackendNames()))
        ->required();
    cmd->add_option("-o,--out", o->out, "Where to write it (default: print it)");
    cmd->callback([o] {
      RunGuarded([&] {
        const std::string text = RigTemplate(o->device);
        runner::ParseRig(text, "<template>");  // what `rig show` will read
        PrintOrWrite(text, o->out);
        return kExitOk;
      });
    });
  }
  auto o = std::make_shared<TouchArgs>();
  auto* cmd = rig.add_subcommand(
      "touch",
      "Stream the tool tip's position (device frame; with --rig also the sample frame) and\n"
      "record a touch on Enter or a Falcon grip button; writes the points (x_m,y_m,z_m, device\n"
      "frame) that `rig calibrate --points` reads. Touch at least three spread points on one\n"
      "sample, the first two along its x axis.");
  cmd->add_option("--device", o->device, "The device")
      ->check(CLI::IsMember(runner::BackendNames()))
      ->required();
  cmd->add_option("--rig", o->rig, "Rig file: also show the tip in the sample's frame");
  AddEnumOption(cmd, "--side", o->side, kSampleSideNames,
                "Which sample (for the sample frame and --script)");
  cmd->add_option("--points", o->points, "How many touches to record")
      ->check(CLI::Range(3, 100))
      ->capture_default_str();
  cmd->add_option("--firmware", o->firmware, "falcon: the firmware file (docs/hardware.md)");
  cmd->add_option("--script", o->script,
                  "sim and falcon-twin only: the simulated hand touches these points of the\n"
                  "sample (x,y,z in metres, sample frame; a CSV file or \"x,y,z;...\") where the\n"
                  "sample truly lies, and each is recorded (no key presses)");
  cmd->add_option("-o,--out", o->out, "Points file to write (default: print it)");
  cmd->callback([o] { RunGuarded([&] { return RunTouch(*o); }); });
}

}  // namespace hapticlab::cli
