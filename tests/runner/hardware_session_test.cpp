// A hardware session end to end without hardware: a device that strokes the samples in
// circles through the real-time engine, a buffer actuator, the participant's ratings from a
// scripted UI; an injected device fault faults and re-queues the trial.

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <thread>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/force_record.hpp"
#include "hapticlab/db/timing.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/open_rig.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/test/replay_device.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::hardware_session_test {
namespace {

// Strokes in 1 cm circles at 5 cm/s, pressing 0.5 mm into the surface. From the `nan_from`-th
// read on, `nan_count` reads carry NaN (a glitching encoder).
class CirclingDevice : public devices::HapticDevice {
 public:
  std::atomic<long> reads{0};
  long nan_from = -1, nan_count = 0;
  devices::DeviceCapabilities Capabilities() const override {
    return {.name = "circling", .max_force_N = 4};
  }
  void SetTimeBase(std::chrono::steady_clock::time_point t0) noexcept override { t0_ = t0; }
  devices::ReadResult Read(renderer::DeviceSample* out) noexcept override {
    const long k = reads++;
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    const double w = 0.05 / 0.01;
    out->state.p_m = {0.01 * std::cos(w * t), 0.01 * std::sin(w * t), -0.0005};
    out->state.v_mps = {-0.05 * std::sin(w * t), 0.05 * std::cos(w * t), 0};
    if (nan_from >= 0 && k >= nan_from && k < nan_from + nan_count)
      out->state.p_m.x() = std::nan("");
    out->t_s = t;
    return devices::ReadResult::kOk;
  }
  void WriteForce(const Eigen::Vector3d& f) noexcept override {
    if (f.norm() > max_seen) max_seen = f.norm();
  }
  double max_seen = 0;

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

class Rater : public SessionUi {
 public:
  int frames = 0, rated = 0;
  bool Stimulus(const TrialScreen&, int, const Eigen::Vector3d&, double) override {
    ++frames;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return true;  // the stylus may be NaN while a fault is injected; the watchdog handles it
  }
  std::optional<std::vector<double>> Rate(const TrialScreen& t) override {
    ++rated;
    return std::vector<double>(t.criteria.size(), 50.0);
  }
  bool Break(double) override { return true; }
};

// A toy device back-end, registered in this test binary as a lab would add one (one file and
// one registration line in runner/src/backends/; here at run time): its factory keeps a
// circling device and a buffer actuator in the rig.
void RegisterCircling() {
  if (FindBackend("circling")) return;
  RigBackend b;
  b.name = "circling";
  b.kind = DeviceKind::kHardware;
  b.help = "a test device stroking in circles";
  b.open = [](const RigRequest&, const RigFile&, Rig* rig) {
    rig->device = rig->parts.Keep(std::make_unique<CirclingDevice>());
    rig->actuator = rig->parts.Keep(std::make_unique<test::BufferActuator>(10000, 200000));
    return std::string("circling test device");
  };
  RegisterBackend(std::move(b));
}

TEST(HardwareSession, RunsThroughTheEngineAndRecordsTrajectories) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  RegisterCircling();
  const auto rig = OpenRig({.device = "circling"});
  EXPECT_FALSE(GetBackend("circling").simulated());
  const auto& dev = dynamic_cast<const CirclingDevice&>(*rig->device);
  Rater ui;
  RunOptions o;
  o.db_path = dir.File("hw.db");
  o.participant = "P09";
  o.device = "circling";
  o.rig = rig.get();
  o.ui = &ui;
  o.consent_confirmed_by = "E01";  // a person takes part
  o.stop_after_trials = 7;         // the training trials and three rated ones (0.5 s per side)
  const auto s = RunStudy(p, o);
  EXPECT_EQ(s.status, db::SessionStatus::kAborted);
  EXPECT_GT(ui.frames, 10);
  EXPECT_GT(dev.reads.load(), 500) << "the force loop ran";
  EXPECT_LE(dev.max_seen, 4.0 + 1e-9) << "never above the device's limit";
  db::Database d(o.db_path);
  const auto se = d.Sessions(d.Participants(d.Studies()[0].id)[0].id)[0];
  // This session runs on the real clock and its device never faults by itself: on a heavily
  // loaded machine the force loop wakes late (missed deadlines, or no read for over 10 ms),
  // and the watchdog rightly faults those trials. When that left no rated trial, the checks
  // below have nothing to check: the test says so rather than failing on the machine's load
  // (no timed assertions in unit tests).
  std::string faults;
  for (const auto& e : d.Events(se.id))
    if (e.kind == db::EventKind::kDeviceFault) faults += e.detail + "; ";
  if (ui.rated == 0 && !faults.empty())
    GTEST_SKIP() << "every rated trial faulted on the real clock (a loaded machine): " << faults;
  EXPECT_GE(ui.rated, 1);
  int rated_trials = 0, chunks = 0;
  for (const auto& t : d.Trials(se.id)) {
    if (t.status != db::TrialStatus::kCompleted || t.phase == PhaseKind::kTraining) continue;
    ++rated_trials;
    EXPECT_EQ(d.Ratings(t.id).size(), 2u);
    chunks += static_cast<int>(d.TrajectoryChunks(t.id).size());
  }
  EXPECT_EQ(rated_trials, ui.rated);
  EXPECT_GT(chunks, 0) << "force streams recorded";
  // Timing per trial side and loop (real clock): the force loop's threads had 1 ns slack.
  int force_rows = 0;
  for (const auto& t : db::StudySideTimings(d, d.Studies()[0].id)) {
    EXPECT_EQ(t.clock, "real");
    if (t.loop != "force") continue;
    ++force_rows;
    EXPECT_EQ(t.timer_slack_ns, 1);
    EXPECT_GT(t.ticks, 100);
    EXPECT_FALSE(t.late_histogram.empty());
    EXPECT_LE(t.late_p50_us, t.late_p99_us);
    EXPECT_LE(t.late_p99_us, t.late_max_us);
  }
  EXPECT_GE(force_rows, 2 * rated_trials);
  for (const auto& e : d.Events(se.id))  // on a loaded machine: deadline misses (real clock)
    if (e.kind == db::EventKind::kDeviceFault) std::printf("%s\n", e.detail.c_str());
  bool device_logged = false;
  for (const auto& e : d.Events(se.id))
    device_logged |= e.kind == db::EventKind::kDevice &&
                     e.detail.starts_with("circling test device; rig built-in");
  EXPECT_TRUE(device_logged);
  EXPECT_EQ(se.device, "circling");
}

TEST(HardwareSession, AWatchdogFaultRequeuesTheTrial) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  CirclingDevice dev;
  // During the first rated trial: a hardware session first renders one 0.5 s training trial
  // per material at 1 kHz (a fault there is logged, not re-queued), then the rated trials.
  dev.nan_from = static_cast<long>(p.materials.size()) * 500 + 200;
  dev.nan_count = 5;
  Rig rig{.device = &dev, .description = "glitching"};
  Rater ui;
  RunOptions o;
  o.db_path = dir.File("f.db");
  o.participant = "P10";
  o.device = "circling";
  o.rig = &rig;
  o.ui = &ui;
  o.consent_confirmed_by = "E01";  // a person takes part
  o.stop_after_trials = 6;
  const auto s = RunStudy(p, o);
  EXPECT_GE(s.faults, 1);
  db::Database d(o.db_path);
  const auto se = d.Sessions(d.Participants(d.Studies()[0].id)[0].id)[0];
  bool nan_logged = false, requeue = false;
  for (const auto& e : d.Events(se.id)) {
    nan_logged |= e.kind == db::EventKind::kDeviceFault && e.detail.rfind("nan at", 0) == 0;
    requeue |=
        e.kind == db::EventKind::kDeviceFault && e.detail.find("re-queued") != std::string::npos;
  }
  EXPECT_TRUE(nan_logged);
  EXPECT_TRUE(requeue);
  // Without the participant window a hardware session is refused (ratings need a person):
  // a caller's bug (the CLI refuses it as bad input before), so a PreconditionError.
  RunOptions bad = o;
  bad.ui = nullptr;
  bad.participant = "P11";
  EXPECT_THROW(RunStudy(p, bad), PreconditionError);
}

// The Falcon twin: the real Falcon back-end (firmware loader, packets, kinematics, force to
// torque) over the emulated Falcon, driven by the real-time engine with the simulated hand;
// the session runs like a simulated one and its records show contact in the sample frame.
TEST(FalconTwinSession, RunsAWholeSessionThroughTheFalconBackEnd) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  auto sr = OpenRig({.device = "falcon-twin", .rig_file = DefaultRig("falcon")});
  ASSERT_TRUE(sr->sim->twin->firmware_loaded());
  std::uint64_t virtual_sides = 0, contact = 0, ticks = 0;
  RunOptions o;
  o.db_path = dir.File("twin.db");
  o.participant = "T01";
  o.device = "falcon-twin";
  o.rig = sr.get();
  o.record = RecordMode::kForce;
  o.on_side = [&](const SideReport& r) {
    ticks += r.engine.force_ticks;
    contact += r.contact_ticks;
    virtual_sides += r.stimulus.rfind("virtual:", 0) == 0;
    EXPECT_EQ(r.engine.lost_reads, 0u);
  };
  const auto s = RunStudy(p, o);
  ASSERT_EQ(s.status, db::SessionStatus::kCompleted);
  EXPECT_EQ(s.faults, 0);
  EXPECT_GT(virtual_sides, 0u);
  EXPECT_GT(contact, ticks * 8 / 10) << "the hand pressed on the samples through the Falcon";
  EXPECT_GE(dynamic_cast<devices::falcon::FalconDevice&>(*sr->device).packets(), ticks)
      << "one status packet per tick";
  // The recorded force streams: sample-frame positions near the surface, and on virtual
  // sides a normal force above 0.3 N in most samples.
  db::Database d(o.db_path);
  const auto se = d.Sessions(d.Participants(d.Studies()[0].id)[0].id)[0];
  std::size_t n = 0, pressing = 0, near_surface = 0;
  for (const auto& t : d.Trials(se.id)) {
    if (t.phase == PhaseKind::kTraining) continue;
    for (const auto& c : d.TrajectoryChunks(t.id)) {
      const bool virt = (c.stream == "left_force" ? t.left : t.right).rfind("virtual:", 0) == 0;
      for (std::size_t i = 0; i < c.sample_count(); ++i) {
        const float* r = &c.samples[i * c.channels.size()];
        near_surface += std::abs(r[db::Col(db::ForceChannel::kZ_m)]) < 0.01;
        if (!virt) continue;
        ++n;
        pressing += r[db::Col(db::ForceChannel::kNormal_N)] > 0.3f;
      }
    }
  }
  ASSERT_GT(n, 0u);
  EXPECT_GT(pressing, n * 8 / 10);
  EXPECT_GT(near_surface, n);  // every side's samples, real sides included
  const auto prov = se.provenance_json;
  EXPECT_NE(prov.find("file_sha256"), std::string::npos);
  EXPECT_NE(se.calibration.find("[sample.left]"), std::string::npos) << "the rig file is recorded";
}

TEST(FalconTwinSession, ARigFileWrongBy5cmTouchesNothingAndSaysSo) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  RigFile wrong = DefaultRig("falcon");
  for (auto& w : wrong.world_from_sample)
    w.translation() -= w.linear().col(2) * 0.05;  // 5 cm below the truth
  auto sr = OpenRig({.device = "falcon-twin", .rig_file = wrong});
  RunOptions o;
  o.db_path = dir.File("wrong.db");
  o.participant = "T02";
  o.device = "falcon-twin";
  o.rig = sr.get();
  o.record = RecordMode::kNone;
  const auto s = RunStudy(p, o);
  EXPECT_EQ(s.status, db::SessionStatus::kAborted);
  EXPECT_EQ(s.completed, 4) << "only the (unrendered) training trials";
  db::Database d(o.db_path);
  const auto se = d.Sessions(d.Participants(d.Studies()[0].id)[0].id)[0];
  int untouched = 0;
  bool abort_says_why = false;
  for (const auto& e : d.Events(se.id)) {
    untouched += e.kind == db::EventKind::kDeviceFault &&
                 e.detail.find("nothing was touched") != std::string::npos;
    abort_says_why |= e.kind == db::EventKind::kAbort &&
                      e.detail.find("sample poses are probably wrong") != std::string::npos;
  }
  EXPECT_EQ(untouched, 3);
  EXPECT_TRUE(abort_says_why);
  for (const auto& t : d.Trials(se.id))
    EXPECT_TRUE(d.Ratings(t.id).empty()) << "no silent trial was rated";
}

}  // namespace
}  // namespace hapticlab::runner::hardware_session_test
