// hapticlab rig: the rig file's frames and calibration (show, calibrate).

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/runner/open_rig.hpp"
#include "hapticlab/runner/rig.hpp"
#include "hapticlab/runner/rt_engine.hpp"
#include "hapticlab/sim/sim_lab.hpp"
#include "rig_timing.hpp"

namespace hapticlab::cli {
namespace {

using nlohmann::json;
const char* const kSides[2] = {"left", "right"};

json Vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

runner::RigFile LoadOrDefault(const std::string& path, const std::string& device) {
  return path.empty() ? runner::DefaultRig(device) : runner::LoadRig(path);
}

}  // namespace

// Touch points [m, device frame]: a CSV file (x_m,y_m,z_m per line, an optional header) or
// "x,y,z;x,y,z;...".
std::vector<Eigen::Vector3d> ParseTouchPoints(const std::string& arg) {
  std::vector<Eigen::Vector3d> pts;
  const bool inline_list = arg.find(';') != std::string::npos || !std::ifstream(arg);
  const std::string src = inline_list ? "--points" : arg;
  std::string text = inline_list ? arg : ReadTextFile(arg, "points file");
  if (inline_list) std::replace(text.begin(), text.end(), ';', '\n');
  std::istringstream in(text);
  std::string line;
  int n = 0;
  Diagnostics d;
  while (std::getline(in, line)) {
    ++n;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    double x, y, z;
    char c1, c2;
    std::istringstream ls(line);
    if (ls >> x >> c1 >> y >> c2 >> z && c1 == ',' && c2 == ',' && std::isfinite(x) &&
        std::isfinite(y) && std::isfinite(z)) {
      pts.emplace_back(x, y, z);
    } else if (n == 1 && !inline_list && line.find('x') != std::string::npos) {
      continue;  // header
    } else {
      d.Add(src, n, "point", "expected x,y,z in metres, got '" + line + "'");
    }
  }
  d.ThrowIfAny();
  return pts;
}

namespace {

// rig check --clock: the stroke check on the virtual clock, or the timing check on the real one.
enum class CheckClock { kVirtual, kReal };
inline constexpr EnumTable<CheckClock, 2> kCheckClockNames{
    {{CheckClock::kVirtual, "virtual"}, {CheckClock::kReal, "real"}}};

struct CheckArgs {
  std::string path, device = DefaultCheckDevice(), firmware;
  std::optional<CheckClock> clock;  ///< none given: real for hardware, else virtual
  double seconds = 2, empty = 0, split = 0;
  bool json = false, no_vibration = false;
  TimingCheckArgs timing;
};

// rig check --clock virtual: the simulated hand strokes a virtual sample on the left pose of
// the rig file, on the engine's virtual clock; whether the grip's rest pose touches a sample.
int RunVirtualCheck(const CheckArgs& a, const runner::RigBackend& backend) {
  const auto rf = LoadOrDefault(a.path, backend.RigDevice());
  runner::RigRequest q{.device = a.device, .rig_file = rf};
  q.generic.empty_read_probability = a.empty;
  q.twin.empty_read_probability = a.empty;
  q.twin.split_probability = a.split;
  const auto sr = runner::OpenRig(q);
  const auto model = sim::PlaceholderModel(sim::MaterialProfile{.id = "check"});
  renderer::RenderOptions ro;
  ro.device_max_stiffness_N_per_m = sr->device->Capabilities().max_stiffness_N_per_m;
  ro.max_force_N = std::min(ro.max_force_N, sr->device->Capabilities().max_force_N);
  // The rest pose: in contact when the model pushes on the grip there (either sample).
  bool home_in_contact = false;
  for (int s = 0; s < 2; ++s) {
    renderer::HybridRenderer probe(model, ro);
    renderer::DeviceSample ds;
    ds.state.p_m =
        sr->device_from_sample[static_cast<std::size_t>(s)].inverse() * backend.home_position_m;
    home_in_contact |= probe.ForceTick(ds, 0).raw.normal_force_N > 0.3;
  }
  renderer::HybridRenderer r(model, ro);
  Rng rng(1);
  sr->sim->hand.Begin(
      sim::DrawStroke(rng), sr->sim->true_device_from_sample[0],
      model.contact.layer_thickness_m + model.geometry->max_m() - model.geometry->min_m(),
      model.contact.texture.K + 0.5 * ro.device_max_stiffness_N_per_m, nullptr, ro.force_rate_hz,
      ro.vibration_rate_hz);
  if (sr->sim->twin) sr->sim->twin->BeginRun();
  runner::EngineOptions eo;
  eo.virtual_clock = &sr->sim->clock;
  eo.sample_from_device = sr->device_from_sample[0].inverse();
  runner::RtEngine engine(r, *sr->device, &sr->sim->actuator, eo);
  engine.RunFor(std::chrono::duration<double>(a.seconds));
  const auto st = engine.Stats();
  json j = {{"device", a.device},
            {"rig", rf.path.empty() ? "built-in" : rf.path},
            {"rig_sha256", rf.sha256},
            {"seconds", a.seconds},
            {"ticks", st.force_ticks},
            {"vibration_ticks", st.vibration_ticks},
            {"empty_reads", st.empty_reads},
            {"lost", st.lost_reads},
            {"faulted", engine.watchdog().tripped()},
            {"contact_ticks", st.contact_ticks},
            {"home_in_contact", home_in_contact},
            // The timing keys of --clock real, for one schema: a virtual clock has no lateness.
            {"clock", "virtual"},
            {"force_rate_hz", st.achieved_force_rate_hz},
            {"jitter_us", {{"p50", 0.0}, {"p99", 0.0}, {"p999", 0.0}, {"max", 0.0}}},
            {"misses", st.force_deadline_misses},
            {"underruns", st.audio_underruns},
            {"priority", "virtual clock"},
            {"memory_locked", st.memory.locked},
            {"timer_slack_ns", nullptr}};
  if (const auto* falcon = dynamic_cast<const devices::falcon::FalconDevice*>(sr->device)) {
    j["falcon_packets"] = falcon->packets();
    j["falcon_empty_reads"] = falcon->empty_reads();
    j["falcon_lost_reads"] = falcon->lost_reads();
    j["falcon_malformed_packets"] = falcon->malformed_packets();
    j["twin_split_packets"] = sr->sim->twin->split_packets();
  }
  if (a.json) {
    PrintJson(j);
  } else {
    fmt::print(
        "{} on rig {}: {} ticks, {} empty reads, {} lost, {} in contact, {}; rest pose {}\n",
        a.device, j["rig"].get<std::string>(), st.force_ticks, st.empty_reads, st.lost_reads,
        st.contact_ticks, engine.watchdog().tripped() ? "FAULTED" : "no fault",
        home_in_contact ? "IN CONTACT with a sample (check the rig file)" : "out of contact");
  }
  return home_in_contact || engine.watchdog().tripped() ? kExitFailure : kExitOk;
}

void RegisterRigShow(CLI::App& rig) {
  struct O {
    std::string path, device = runner::DefaultBackendName();
    bool json = false;
  };
  auto o = std::make_shared<O>();
  auto* cmd = rig.add_subcommand(
      "show", "Print a rig file's frames: each sample's pose in the world and device frames");
  cmd->add_option("RIG", o->path, "Rig file (.toml); none: the built-in rig of --device");
  cmd->add_option("--device", o->device, "Built-in rig to show when no file is given")
      ->check(CLI::IsMember(runner::BackendNames()))
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "Print as JSON");
  cmd->callback([o] {
    RunGuarded([&] {
      const auto r = LoadOrDefault(o->path, o->device);
      json sides = json::object();
      for (int s = 0; s < 2; ++s) {
        const auto T = r.DeviceFromSample(s);
        const auto& W = r.world_from_sample[static_cast<std::size_t>(s)];
        sides[kSides[s]] = {{"world",
                             {{"origin_m", Vec(W.translation())},
                              {"x_axis", Vec(W.linear().col(0))},
                              {"z_axis", Vec(W.linear().col(2))}}},
                            {"device",
                             {{"origin_m", Vec(T.translation())},
                              {"x_axis", Vec(T.linear().col(0))},
                              {"z_axis", Vec(T.linear().col(2))}}}};
      }
      const json j = {{"file", r.path.empty() ? "(built-in " + o->device + " rig)" : r.path},
                      {"sha256", r.sha256},
                      {"device", r.device},
                      {"tip_offset_m", Vec(r.tip_offset_m)},
                      {"motor_units_per_Nm", r.motor_units_per_Nm},
                      {"max_force_N", r.max_force_N},
                      {"samples", sides}};
      if (o->json) {
        PrintJson(j);
        return kExitOk;
      }
      fmt::print("rig {} (sha256 {}), device {}\n", j["file"].get<std::string>(),
                 r.sha256.substr(0, 16), r.device);
      fmt::print(
          "stylus tip offset {} m (device frame); force calibration {} motor units per N m{}\n",
          Vec(r.tip_offset_m).dump(), r.motor_units_per_Nm,
          r.max_force_N > 0 ? fmt::format("; force limit {} N", r.max_force_N) : "");
      for (int s = 0; s < 2; ++s) {
        const auto T = r.DeviceFromSample(s);
        fmt::print("{:<5} sample: origin {} m, normal {} in the device frame (tip)\n", kSides[s],
                   Vec(T.translation()).dump(), Vec(T.linear().col(2)).dump());
      }
      return kExitOk;
    });
  });
}

void RegisterRigCheck(CLI::App& rig) {
  auto o = std::make_shared<CheckArgs>();
  auto* cmd = rig.add_subcommand(
      "check",
      "--clock virtual (the default for sim and falcon-twin): run a simulated rig through the "
      "real-time engine on a virtual\n"
      "clock: the simulated hand strokes a virtual sample on the left pose of the rig file;\n"
      "reports the ticks, the link's empty and lost reads, contact, and whether the grip's rest\n"
      "pose is already in contact with a sample (a wrong rig file).\n"
      "--clock real (the only clock for falcon, dhd, openhaptics; zero force on hardware):\n"
      "run the force loop (at --rate) and the 10 kHz vibration loop on the real\n"
      "clock with a resting simulated grip (zero force; --render MODEL: a simulated hand "
      "strokes\n"
      "the rendered model) and the chosen actuator, and print a\n"
      "histogram of wake-up lateness like cyclictest, what the threads got (priority, memory\n"
      "lock, timer slack) and the verdict for the rate (exit 1: a missed deadline or a rate\n"
      "off by more than 1 %).");
  cmd->add_option("--device", o->device, DeviceHelp("Device back-end"))
      ->check(CLI::IsMember(runner::BackendNames()))
      ->capture_default_str();
  AddEnumOption(cmd, "--clock", o->clock, kCheckClockNames,
                "virtual: the stroke check (simulated rigs; their default); real: the timing "
                "check (hardware's default)");
  cmd->add_option("--firmware", o->firmware, "falcon: the firmware file (docs/hardware.md)");
  cmd->add_option("--rate", o->timing.rate_hz, "--clock real: force loop rate [Hz]")
      ->check(CLI::Range(100.0, 20000.0))
      ->capture_default_str();
  AddEnumOption(cmd, "--actuator", o->timing.actuator, runner::kActuatorNames,
                "--clock real: vibrotactile actuator (audio: PortAudio)");
  cmd->add_option("--audio-device", o->timing.audio_device,
                  "--clock real: PortAudio output device (name substring)");
  cmd->add_flag("--no-vibration", o->no_vibration, "--clock real: run the force loop only");
  cmd->add_option(
         "--render", o->timing.render,
         "--clock real: render this material model (.toml) while a simulated hand strokes the\n"
         "virtual sample (default: a resting grip out of contact, zero force)")
      ->check(CLI::ExistingFile);
  AddRtOptions(cmd, o->timing.rt);
  cmd->add_option("--rig", o->path, "Rig file (default: the device's built-in rig)");
  cmd->add_option("--seconds", o->seconds, "Stroking time [s] (virtual)")
      ->check(CLI::Range(0.01, 600.0))
      ->capture_default_str();
  cmd->add_option("--empty-reads", o->empty, "Fraction of link reads with no new data")
      ->check(CLI::Range(0.0, 0.9));
  cmd->add_option("--split-packets", o->split,
                  "falcon-twin: fraction of status packets split across two reads")
      ->check(CLI::Range(0.0, 0.9));
  cmd->add_flag(
      "--json", o->json,
      "Print {\"device\", \"ticks\", \"empty_reads\", \"lost\", \"home_in_contact\", ...}");
  cmd->callback([o] {
    RunGuarded([&] {
      const runner::RigBackend& backend = runner::GetBackend(o->device);
      const bool hardware = !backend.simulated();
      if (!o->clock) o->clock = hardware ? CheckClock::kReal : CheckClock::kVirtual;
      if (hardware && o->clock == CheckClock::kVirtual)
        throw InputError(kCommandLine, 0, "--clock",
                         "'" + o->device +
                             "' is hardware: it runs on the real clock (--clock real); the "
                             "virtual-clock check strokes a simulated rig (" +
                             runner::SimulatedBackendList() + ")");
      if (o->clock == CheckClock::kReal) {
        TimingCheckArgs a = o->timing;
        a.device = o->device;
        a.firmware = o->firmware;
        if (!o->path.empty()) a.rig_file = runner::LoadRig(o->path);
        a.seconds = o->seconds;
        a.json = o->json;
        a.vibration = !o->no_vibration;
        return RunTimingCheck(a);
      }
      return RunVirtualCheck(*o, backend);
    });
  });
}

void RegisterRigCalibrate(CLI::App& rig) {
  struct O {
    std::string path, points, out, up;
    SampleSide side = SampleSide::kLeft;
  };
  auto o = std::make_shared<O>();
  auto* cmd = rig.add_subcommand(
      "calibrate",
      "Record a sample's pose from three or more touches on its surface: fits a plane\n"
      "(least squares), prints the residual, and writes the rig file with the new pose.\n"
      "Touches are the device's reported points [m, device frame]; the rig's stylus tip\n"
      "offset is added. +z of the sample is the plane normal on the side of --up (default:\n"
      "the current pose's normal); x points from the first touch to the second.");
  cmd->add_option("RIG", o->path, "Rig file to update (.toml)")->required();
  AddEnumOption(cmd, "--side", o->side, kSampleSideNames, "Which sample");
  cmd->add_option("--points", o->points, "Touches: a CSV file (x_m,y_m,z_m) or \"x,y,z;x,y,z;...\"")
      ->required();
  cmd->add_option("--up", o->up, "Direction out of the sample, device frame: x,y,z");
  cmd->add_option("--out", o->out, "Where to write the updated rig file (default: print it)");
  cmd->callback([o] {
    RunGuarded([&] {
      auto r = runner::LoadRig(o->path);
      const int side = static_cast<int>(o->side);
      auto pts = ParseTouchPoints(o->points);
      for (auto& p : pts) p += r.tip_offset_m;  // the tip, not the reported point
      Eigen::Vector3d up =
          (r.world_from_device.inverse() * r.world_from_sample[static_cast<std::size_t>(side)])
              .linear()
              .col(2);
      if (!o->up.empty()) {
        double x, y, z;
        if (std::sscanf(o->up.c_str(), "%lf,%lf,%lf", &x, &y, &z) != 3)
          throw InputError(kCommandLine, 0, "--up", "expected x,y,z, got '" + o->up + "'");
        up = {x, y, z};
      }
      const auto fit = runner::FitSamplePlane(pts, up);
      r.world_from_sample[static_cast<std::size_t>(side)] =
          r.world_from_device * fit.device_from_sample;
      const std::string text = runner::RigToToml(r);
      fmt::print(stderr,
                 "{} sample from {} touches: origin {} m, normal {} (device frame); residual RMS "
                 "{:.3f} mm, max {:.3f} mm\n",
                 NameOf(kSampleSideNames, o->side), pts.size(),
                 Vec(fit.device_from_sample.translation()).dump(),
                 Vec(fit.device_from_sample.linear().col(2)).dump(), fit.rms_residual_m * 1e3,
                 fit.max_residual_m * 1e3);
      PrintOrWrite(text, o->out);
      return kExitOk;
    });
  });
}

}  // namespace

void RegisterRig(CLI::App& app) {
  auto* rig = app.add_subcommand(
      "rig",
      "The rig file: device and sample frames, stylus tip, force calibration (docs/hardware.md)");
  rig->require_subcommand(1);
  RegisterRigShow(*rig);
  RegisterRigCheck(*rig);
  RegisterRigCalibrate(*rig);
  RegisterRigSetup(*rig);
}

}  // namespace hapticlab::cli
