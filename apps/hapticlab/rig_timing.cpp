#include "rig_timing.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/io.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/devices/audio.hpp"
#include "hapticlab/devices/factory.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/runner/open_rig.hpp"
#include "hapticlab/runner/rig.hpp"
#include "hapticlab/runner/rt_engine.hpp"
#include "hapticlab/sim/falcon_twin.hpp"
#include "hapticlab/sim/sim_device.hpp"
#include "hapticlab/sim/sim_lab.hpp"

namespace hapticlab::cli {
namespace {

using nlohmann::json;

// A grip at rest 5 cm above the device origin (out of contact with any sample): every read
// is a new sample stamped with the real clock since the loops' time zero.
class RestingDevice final : public devices::HapticDevice {
 public:
  devices::DeviceCapabilities Capabilities() const override {
    devices::DeviceCapabilities c;
    c.name = "sim (resting grip)";
    c.max_rate_hz = 20000;
    return c;
  }
  devices::ReadResult Read(renderer::DeviceSample* out) noexcept override {
    out->state.p_m = Eigen::Vector3d(0, 0, 0.05);
    out->state.v_mps = Eigen::Vector3d::Zero();
    out->t_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    return devices::ReadResult::kOk;
  }
  void WriteForce(const Eigen::Vector3d&) noexcept override {}
  void SetTimeBase(std::chrono::steady_clock::time_point t0) noexcept override { t0_ = t0; }

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

// The hardware at zero force: reads pass through, every force command is zero (a timing check
// must not push on the hand holding the grip).
class ZeroForceDevice final : public devices::HapticDevice {
 public:
  explicit ZeroForceDevice(devices::HapticDevice& d) : d_(d) {}
  devices::DeviceCapabilities Capabilities() const override { return d_.Capabilities(); }
  devices::ReadResult Read(renderer::DeviceSample* out) noexcept override { return d_.Read(out); }
  void WriteForce(const Eigen::Vector3d&) noexcept override {
    d_.WriteForce(Eigen::Vector3d::Zero());
  }
  void SetTimeBase(std::chrono::steady_clock::time_point t0) noexcept override {
    d_.SetTimeBase(t0);
  }

 private:
  devices::HapticDevice& d_;
};

// The device the loops drive, and what it needs kept alive.
struct TimingDevice {
  std::unique_ptr<runner::Rig> rig;
  RestingDevice resting;
  std::unique_ptr<ZeroForceDevice> zero;
  devices::HapticDevice* dev = nullptr;
};

// A simulated back-end on the steady clock: without --render a grip at rest (the twin's own
// rest pose; the generic device's grip held out of contact); with --render the simulated hand
// strokes the left sample where it truly lies. Hardware: the device at zero force.
void OpenTimingDevice(const TimingCheckArgs& a, TimingDevice& t) {
  const runner::RigBackend& backend = runner::GetBackend(a.device);
  if (!backend.simulated() && !a.render.empty())
    throw InputError(kCommandLine, 0, "--render",
                     "--render strokes a simulated hand; on hardware the check runs at zero force");
  runner::RigRequest q{.device = a.device, .rig_file = a.rig_file, .firmware = a.firmware};
  q.real_clock = true;
  q.progress = [](const std::string& s) { fmt::print(stderr, "{}\n", s); };
  WithFlags({{"device", "--device"}, {"firmware", "--firmware"}},
            [&] { t.rig = runner::OpenRig(q); });
  if (t.rig->sim) {
    const bool generic = t.rig->sim->generic != nullptr;
    t.dev = generic && a.render.empty() ? static_cast<devices::HapticDevice*>(&t.resting)
                                        : t.rig->device;
    return;
  }
  t.zero = std::make_unique<ZeroForceDevice>(*t.rig->device);
  t.dev = t.zero.get();
}

json Percentiles(const LatencySummary& s) {
  return {{"p50", s.Quantile(0.5) * 1e6},
          {"p99", s.Quantile(0.99) * 1e6},
          {"p999", s.Quantile(0.999) * 1e6},
          {"max", s.max_s * 1e6}};
}

// cyclictest-like: count per microsecond of lateness up to the largest non-empty one (at most
// 100 rows; the rest, with the histogram's overflow bin, in one overflow row).
void PrintHistogram(const LatencySummary& s) {
  constexpr std::size_t kPerUs = 2, kRows = 100;  // two 0.5 us bins per row
  std::uint64_t beyond = 0;
  const auto rows = s.Rows(kPerUs, kRows, &beyond);
  for (std::size_t row = 0; row < rows.size(); ++row)
    fmt::print("  {:>4} us  {:>9}\n", row, rows[row]);
  if (beyond) fmt::print("  >{:>3} us  {:>9}\n", kRows - 1, beyond);
}

// The check's report: rate, thread, lateness and tick-duration quantiles, the lateness
// histogram and the verdict (or the same as JSON).
void ReportTiming(const TimingCheckArgs& a, const runner::EngineStats& st,
                  const runner::EngineTiming& tm, const std::string& verdict, bool ok) {
  const double period_s = 1.0 / a.rate_hz;
  if (a.json) {
    json j = {{"device", a.device},
              {"render", a.render.empty() ? json(nullptr) : json(a.render)},
              {"contact_ticks", st.contact_ticks},
              {"clock", "real"},
              {"seconds", a.seconds},
              {"requested_rate_hz", a.rate_hz},
              {"force_rate_hz", st.achieved_force_rate_hz},
              {"force_ticks", st.force_ticks},
              {"jitter_us", Percentiles(tm.force_late)},
              {"tick_us", Percentiles(tm.force_tick)},
              {"misses", st.force_deadline_misses},
              {"underruns", st.audio_underruns},
              {"priority", st.force_thread.priority_status},
              {"priority_granted", st.force_thread.fifo},
              {"memory_locked", st.memory.locked},
              {"memory_status", st.memory.status},
              {"affinity", st.force_thread.affinity_status},
              {"timer_slack_ns", st.force_thread.timer_slack_ns},
              {"spin_us", a.rt.spin_us},
              {"verdict", verdict},
              {"ok", ok}};
    if (a.vibration)
      j["vibration"] = {{"rate_hz", st.achieved_vibration_rate_hz},
                        {"jitter_us", Percentiles(tm.vibration_late)},
                        {"misses", st.vibration_deadline_misses},
                        {"timer_slack_ns", st.vibration_thread.timer_slack_ns}};
    PrintJson(j);
    return;
  }
  fmt::print("force loop: {:.1f} Hz achieved of {:.0f} Hz over {} s ({} ticks); spin {} us\n",
             st.achieved_force_rate_hz, a.rate_hz, a.seconds, st.force_ticks, a.rt.spin_us);
  if (!a.render.empty())
    fmt::print("rendering {} with a simulated hand stroking it: in contact on {} of {} ticks\n",
               a.render, st.contact_ticks, st.force_ticks);
  fmt::print("thread: {}; affinity {}; memory {}; timer slack {} ns\n",
             st.force_thread.priority_status, st.force_thread.affinity_status, st.memory.status,
             st.force_thread.timer_slack_ns);
  fmt::print(
      "wake-up lateness [us]: p50 {:.1f}, p99 {:.1f}, p99.9 {:.1f}, max {:.1f}; deadline misses "
      "{}\n",
      tm.force_late.Quantile(0.5) * 1e6, tm.force_late.Quantile(0.99) * 1e6,
      tm.force_late.Quantile(0.999) * 1e6, tm.force_late.max_s * 1e6, st.force_deadline_misses);
  fmt::print("tick duration [us]: p50 {:.1f}, p99 {:.1f}, max {:.1f}; audio underruns {}\n",
             tm.force_tick.Quantile(0.5) * 1e6, tm.force_tick.Quantile(0.99) * 1e6,
             tm.force_tick.max_s * 1e6, st.audio_underruns);
  fmt::print("histogram of wake-up lateness (1 us rows, ticks):\n");
  PrintHistogram(tm.force_late);
  fmt::print("verdict: {} (period {:.0f} us)\n", verdict, period_s * 1e6);
}

}  // namespace

void PrintOrWrite(const std::string& text, const std::string& out) {
  if (out.empty()) {
    fmt::print("{}", text);
    return;
  }
  WriteTextFile(out, text);
  fmt::print(stderr, "wrote {}\n", out);
}

std::string DeviceHelp(const std::string& what) {
  std::string s = what + ":";
  const auto backends = runner::Backends();
  for (std::size_t i = 0; i < backends.size(); ++i)
    s += fmt::format("{}\n  {} ({})", i == 0 ? "" : ",", backends[i]->name, backends[i]->help);
  return s;
}

std::string DefaultCheckDevice() {
  for (const auto* b : runner::Backends())
    if (b->simulated() && !b->rig_device.empty()) return b->name;
  return runner::DefaultBackendName();
}

void AddRtOptions(CLI::App* cmd, runner::RtThreadOptions& rt) {
  cmd->add_option(
         "--rt-priority", rt.priority,
         "SCHED_FIFO priority of the force loop (the vibration loop gets one less); 0: normal\n"
         "scheduling. Needs rtprio in limits.conf or CAP_SYS_NICE (docs/hardware.md); a refusal "
         "is\n"
         "reported and the loops run at normal priority")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--spin-us", rt.spin_us,
                  "Busy-wait this long before each force-loop deadline [us] (0: sleep only)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 500.0));
  cmd->add_flag("--lock-memory", rt.lock_memory,
                "mlockall(MCL_CURRENT|MCL_FUTURE) before the loops start (needs memlock)");
  cmd->add_option("--cpu", rt.cpu,
                  "Pin the force loop to this CPU (the vibration loop to the next); -1: no pinning")
      ->capture_default_str()
      ->check(CLI::Range(-1, 1023));
}

int RunTimingCheck(const TimingCheckArgs& a) {
  TimingDevice td;
  OpenTimingDevice(a, td);
  devices::HapticDevice& dev = *td.dev;
  const auto model = a.render.empty() ? sim::PlaceholderModel(sim::MaterialProfile{.id = "check"})
                                      : renderer::LoadMaterial(a.render);
  renderer::RenderOptions ro;
  ro.force_rate_hz = a.rate_hz;
  ro.vibration = a.vibration;
  if (td.dev != &td.resting) {  // the device's own limits (the resting grip has none)
    ro.device_max_stiffness_N_per_m = dev.Capabilities().max_stiffness_N_per_m;
    ro.max_force_N = std::min(ro.max_force_N, dev.Capabilities().max_force_N);
  }
  renderer::HybridRenderer r(model, ro);
  // Without a model: a grip resting out of contact. With one: the simulated hand strokes the
  // virtual left sample where it truly lies, back and forth on the real clock.
  sim::SimRig* simulation = td.rig->sim;
  const Eigen::Isometry3d device_from_sample =
      simulation ? simulation->true_device_from_sample[0] : Eigen::Isometry3d::Identity();
  if (!a.render.empty()) {
    Rng rng(1);
    sim::Stroke stroke = sim::DrawStroke(rng);
    const double relief_m =
        model.geometry ? model.geometry->max_m() - model.geometry->min_m() : 0.0;
    simulation->hand.Begin(stroke, device_from_sample, model.contact.layer_thickness_m + relief_m,
                           model.contact.texture.K + 0.5 * ro.device_max_stiffness_N_per_m, nullptr,
                           ro.force_rate_hz, ro.vibration_rate_hz);
    if (simulation->twin) simulation->twin->BeginRun();
  }
  std::unique_ptr<devices::AudioOutput> audio;
  if (a.actuator == runner::ActuatorKind::kAudio) {
    devices::AudioConfig c;
    c.device = a.audio_device;
    c.input_rate_hz = ro.vibration_rate_hz;
    audio = std::make_unique<devices::AudioOutput>(c, devices::OpenPortAudio());
    audio->Start();
  }
  runner::EngineOptions eo;
  eo.rt = a.rt;
  eo.sample_from_device = device_from_sample.inverse();
  runner::RtEngine engine(r, dev, audio.get(), eo);
  engine.RunFor(std::chrono::duration<double>(a.seconds));
  if (audio) audio->Stop();
  const auto st = engine.Stats();
  const auto tm = engine.Timing();
  // The verdict: the loop kept its rate (within 1 %) and never started a tick a whole period late.
  const bool rate_ok = std::abs(st.achieved_force_rate_hz - a.rate_hz) <= 0.01 * a.rate_hz;
  const bool ok = rate_ok && st.force_deadline_misses == 0;
  const std::string verdict =
      ok ? fmt::format("ok for {:.0f} Hz", a.rate_hz)
         : fmt::format("NOT ok for {:.0f} Hz ({})", a.rate_hz,
                       rate_ok ? fmt::format("{} deadline misses", st.force_deadline_misses)
                               : fmt::format("achieved {:.1f} Hz", st.achieved_force_rate_hz));
  ReportTiming(a, st, tm, verdict, ok);
  return ok ? kExitOk : kExitFailure;
}

}  // namespace hapticlab::cli
