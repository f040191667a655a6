// A hardware session end to end without hardware: a device that strokes the samples in
// circles through the real-time engine, a buffer actuator, the participant's ratings from a
// scripted UI; an injected device fault faults and re-queues the trial.

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <cmath>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/devices/replay.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner {
namespace {

// Strokes in 1 cm circles at 5 cm/s, pressing 0.5 mm into the surface. From the `nan_from`-th
// read on, `nan_count` reads carry NaN (a glitching encoder).
class CirclingDevice : public devices::HapticDevice {
 public:
  std::atomic<long> reads{0};
  long nan_from = -1, nan_count = 0;
  devices::DeviceCapabilities Capabilities() const override { return {.name = "circling", .max_force_N = 4}; }
  void SetTimeBase(std::chrono::steady_clock::time_point t0) noexcept override { t0_ = t0; }
  bool Read(renderer::DeviceSample* out) noexcept override {
    const long k = reads++;
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    const double w = 0.05 / 0.01;
    out->state.p_m = {0.01 * std::cos(w * t), 0.01 * std::sin(w * t), -0.0005};
    out->state.v_mps = {-0.05 * std::sin(w * t), 0.05 * std::cos(w * t), 0};
    if (nan_from >= 0 && k >= nan_from && k < nan_from + nan_count) out->state.p_m.x() = std::nan("");
    out->t_s = t;
    return true;
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

TEST(HardwareSession, RunsThroughTheEngineAndRecordsTrajectories) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  CirclingDevice dev;
  devices::BufferActuator act(10000, 200000);
  HardwareRig rig{.device = &dev, .actuator = &act, .description = "circling test device"};
  Rater ui;
  RunOptions o;
  o.db_path = dir.File("hw.db");
  o.participant = "P09";
  o.device = "circling";
  o.rig = &rig;
  o.ui = &ui;
  o.stop_after_trials = 7;  // the training trials and three rated ones (0.5 s per side)
  const auto s = RunStudy(p, o);
  EXPECT_EQ(s.status, "aborted");
  EXPECT_GE(ui.rated, 1);
  EXPECT_GT(ui.frames, 10);
  EXPECT_GT(dev.reads.load(), 500) << "the force loop ran";
  EXPECT_LE(dev.max_seen, 4.0 + 1e-9) << "never above the device's limit";
  db::Database d(o.db_path);
  const auto se = d.Sessions(d.Participants(d.Studies()[0].id)[0].id)[0];
  int rated_trials = 0, chunks = 0;
  for (const auto& t : d.Trials(se.id)) {
    if (t.status != db::kTrialCompleted || t.phase == "training") continue;
    ++rated_trials;
    EXPECT_EQ(d.Ratings(t.id).size(), 2u);
    chunks += static_cast<int>(d.TrajectoryChunks(t.id).size());
  }
  EXPECT_EQ(rated_trials, ui.rated);
  EXPECT_GT(chunks, 0) << "force streams recorded";
  bool device_logged = false;
  for (const auto& e : d.Events(se.id)) device_logged |= e.kind == "device" && e.detail == "circling test device";
  EXPECT_TRUE(device_logged);
}

TEST(HardwareSession, AWatchdogFaultRequeuesTheTrial) {
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  CirclingDevice dev;
  dev.nan_from = 200;  // during the first rated trial
  dev.nan_count = 5;
  HardwareRig rig{.device = &dev, .description = "glitching"};
  Rater ui;
  RunOptions o;
  o.db_path = dir.File("f.db");
  o.participant = "P10";
  o.device = "circling";
  o.rig = &rig;
  o.ui = &ui;
  o.stop_after_trials = 6;
  const auto s = RunStudy(p, o);
  EXPECT_GE(s.faults, 1);
  db::Database d(o.db_path);
  const auto se = d.Sessions(d.Participants(d.Studies()[0].id)[0].id)[0];
  bool nan_logged = false, requeue = false;
  for (const auto& e : d.Events(se.id)) {
    nan_logged |= e.kind == "device-fault" && e.detail.rfind("nan at", 0) == 0;
    requeue |= e.kind == "device-fault" && e.detail.find("re-queued") != std::string::npos;
  }
  EXPECT_TRUE(nan_logged);
  EXPECT_TRUE(requeue);
  // Without the participant window a hardware session is refused (ratings need a person).
  RunOptions bad = o;
  bad.ui = nullptr;
  bad.participant = "P11";
  EXPECT_THROW(RunStudy(p, bad), InputError);
}

}  // namespace
}  // namespace hapticlab::runner
