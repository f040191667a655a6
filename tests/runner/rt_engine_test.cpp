#include "hapticlab/runner/rt_engine.hpp"

#include <gtest/gtest.h>

#include <optional>

#include "../renderer/test_materials.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/test/replay_device.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::rt_engine_test {
namespace {

// A 0.4 s stroke at 5 cm/s, 0.2 mm below the base top, sampled at 4 kHz.
std::vector<test::TrajectorySample> Stroke(double seconds = 0.4) {
  std::vector<test::TrajectorySample> s;
  for (int k = 0; k <= static_cast<int>(seconds * 4000); ++k) {
    test::TrajectorySample x;
    x.t_s = k / 4000.0;
    x.p_m = {0.05 * x.t_s, 0, -0.2e-3};
    x.v_mps = {0.05, 0, 0};
    s.push_back(x);
  }
  return s;
}

thread_local std::optional<test::NoAllocGuard> t_guard;

TEST(RtEngine, LoopsRunAllocationFreeRecordAndStopAtDisconnect) {
  test::TempDir dir;
  std::int64_t trial;
  {
    db::Database d(dir.File("e.db"));
    const auto se =
        test::AddStudySession(d, {.name = "e", .protocol_toml = "x", .seed = 1}).session;
    trial = d.AddTrial({.session_id = se, .phase = PhaseKind::kMain, .material = "m"});
  }
  const auto m = test::TexturedMaterial();
  renderer::RenderOptions ro;
  ro.force_rate_hz = 1000;
  ro.vibration_rate_hz = 10000;
  ro.max_force_N = 3.0;
  renderer::HybridRenderer r(m, ro);
  RtEngine* engine_ptr = nullptr;
  test::ReplayDevice dev(Stroke(), [&] { return engine_ptr->Now(); });
  test::BufferActuator act(10000, 20000);
  std::atomic<std::uint64_t> allocations{0};
  std::atomic<int> threads_checked{0};
  EngineOptions eo;
  // Both loops guard their own thread; Eigen's heap flag is process-wide, so it is set once
  // here, before the loops start.
  eo.on_thread_enter = [] { t_guard.emplace(test::NoAllocGuard::EigenHeap::kLeave); };
  eo.on_thread_exit = [&] {
    allocations += t_guard->count();
    t_guard.reset();
    ++threads_checked;
  };
  db::TrajectoryWriter writer(dir.File("e.db"));
  auto* fs = writer.OpenStream(trial, "force", ro.force_rate_hz, ForceStreamChannels());
  auto* vs = writer.OpenStream(trial, "vibration", ro.vibration_rate_hz, VibrationStreamChannels());
  RtEngine engine(r, dev, &act, eo, fs, vs);
  engine_ptr = &engine;
  {
    test::EigenNoMalloc no_eigen_heap;
    engine.RunFor(std::chrono::seconds(5));  // the replay ends after 0.4 s: disconnect stops it
  }
  writer.CloseStream(fs);
  writer.CloseStream(vs);

  const auto st = engine.Stats();
  EXPECT_EQ(threads_checked.load(), 2);
  EXPECT_EQ(allocations.load(), 0u) << "a loop allocated";
  EXPECT_GE(st.disconnects, 1u);
  EXPECT_GT(st.force_ticks, 100u);
  EXPECT_GT(st.vibration_ticks, 1000u);
  EXPECT_EQ(st.recording_overflows, 0u);
  // Every commanded force is within the limit. The device logged one force per loop tick
  // (tick k at index k - 1), then Stop's closing zero.
  const auto& forces = dev.forces();
  ASSERT_EQ(forces.size(), st.force_ticks + 1);
  for (const auto& f : forces) ASSERT_LE(f.norm(), ro.max_force_N * (1 + 1e-12));
  // Tick k wakes no earlier than k ms: from tick 401 on, the replay (0.4 s) has ended and
  // every read is lost. The loop itself must command zero on each of those ticks, from the
  // first one on, before the disconnect (the tenth lost read) stops it; Stop's zero is not
  // among them. Before, the stylus pushed (0.2 mm deep, after the force filter's rise).
  ASSERT_GT(st.force_ticks, 400u);
  std::size_t pushing = 0;
  for (std::size_t k = 100; k <= 400; ++k) pushing += forces[k - 1].norm() > 0.05;
  EXPECT_GT(pushing, 150u) << "the stroke pushed before the link was lost";
  for (std::size_t k = 401; k <= st.force_ticks; ++k)
    ASSERT_EQ(forces[k - 1].norm(), 0.0) << "force tick " << k << " after the replay ended";
  // The recording holds what the loops did.
  db::Database d(dir.File("e.db"));
  std::size_t force_samples = 0, vib_samples = 0;
  for (const auto& c : d.TrajectoryChunks(trial))
    (c.stream == "force" ? force_samples : vib_samples) += c.sample_count();
  EXPECT_EQ(force_samples, st.force_ticks);
  EXPECT_EQ(vib_samples, st.vibration_ticks);
  // Each force sample carries how late its tick ran: a loop never wakes before its deadline,
  // and waking takes time.
  double late_max = 0;
  for (const auto& c : d.TrajectoryChunks(trial))
    if (c.stream == "force") {
      ASSERT_EQ(c.channels.back(), "late_s");
      for (std::size_t i = 0; i < c.sample_count(); ++i) {
        const float late = c.samples[i * c.channels.size() + 15];
        EXPECT_GE(late, 0.f);
        late_max = std::max(late_max, static_cast<double>(late));
      }
    }
  EXPECT_GT(late_max, 0.0);
  std::printf(
      "force %.0f Hz, vibration %.0f Hz, force jitter max %.1f us mean %.1f us, misses %llu/%llu\n",
      st.achieved_force_rate_hz, st.achieved_vibration_rate_hz, st.force_jitter_max_s * 1e6,
      st.force_jitter_mean_s * 1e6, static_cast<unsigned long long>(st.force_deadline_misses),
      static_cast<unsigned long long>(st.vibration_deadline_misses));
}

// A device whose data never changes its time stamp: the renderer sees it go stale. Logs
// every commanded force with the clock's time (preallocated).
class FrozenDevice : public devices::HapticDevice {
 public:
  explicit FrozenDevice(const devices::Clock& clock) : clock_(clock) { forces.reserve(1000); }
  devices::DeviceCapabilities Capabilities() const override { return {}; }
  devices::ReadResult Read(renderer::DeviceSample* out) noexcept override {
    out->state.p_m = {0, 0, -0.5e-3};
    out->t_s = 0;  // measured once, never again
    return devices::ReadResult::kOk;
  }
  void WriteForce(const Eigen::Vector3d& f) noexcept override {
    if (forces.size() < forces.capacity()) forces.push_back({clock_.Now(), f.norm()});
  }
  std::vector<std::pair<double, double>> forces;  // (tick time [s], |force| [N])

 private:
  const devices::Clock& clock_;
};

TEST(RtEngine, StaleDeviceDataDrivesForceToZeroOnTheNextTick) {
  const auto m = test::TexturedMaterial();
  renderer::RenderOptions ro;
  ro.vibration = false;
  ro.stale_after_s = 0.01;
  renderer::HybridRenderer r(m, ro);
  devices::VirtualClock clock;
  FrozenDevice dev(clock);
  EngineOptions eo;
  eo.virtual_clock = &clock;
  RtEngine engine(r, dev, nullptr, eo);
  engine.Start();
  {
    test::NoAllocGuard guard;
    engine.AdvanceTo(0.1);
    EXPECT_EQ(guard.count(), 0u);
  }
  // The loop's own commands (Stop's closing zero comes later): 100 ticks at 1 kHz.
  const auto loop_forces = dev.forces;
  engine.Stop();
  EXPECT_GT(r.counters().stale_faults.load() + engine.Stats().stale_faults, 0u);
  ASSERT_EQ(loop_forces.size(), 100u);
  // The stylus is 0.5 mm in: the first ticks push. From the first tick whose data is older
  // than 10 ms (t = 11 ms, data stamped 0 s) every command is zero.
  std::size_t pushing = 0;
  for (const auto& [t, f] : loop_forces) {
    if (t < 0.0095) pushing += f > 0;
    if (t > 0.0105) {
      EXPECT_EQ(f, 0.0) << "stale data at " << t << " s still pushes";
    }
  }
  EXPECT_GT(pushing, 5u) << "the stylus pushed before its data went stale";
}

}  // namespace
}  // namespace hapticlab::runner::rt_engine_test

namespace hapticlab::runner::rt_engine_test {
namespace {

// A stylus held 0.2 mm into the surface, read over a link that returns no new data on a
// fraction of reads (at random, fixed seed) and is lost for a window of time. Records every
// commanded force with its tick's time (preallocated).
class FlakyLink : public devices::HapticDevice {
 public:
  FlakyLink(const devices::Clock& clock, double empty_fraction, double lost_from_s,
            double lost_for_s)
      : clock_(clock),
        empty_(empty_fraction),
        lost_from_(lost_from_s),
        lost_to_(lost_from_s + lost_for_s) {
    forces.reserve(10000);
  }
  devices::DeviceCapabilities Capabilities() const override { return {.name = "flaky"}; }
  devices::ReadResult Read(renderer::DeviceSample* out) noexcept override {
    t_ = clock_.Now();
    if (t_ >= lost_from_ && t_ < lost_to_) return devices::ReadResult::kLost;
    if (rng_.Uniform() < empty_) return devices::ReadResult::kNoNewData;
    out->state.p_m = {0.05 * t_, 0, -0.2e-3};
    out->state.v_mps = {0.05, 0, 0};
    out->t_s = t_;
    return devices::ReadResult::kOk;
  }
  void WriteForce(const Eigen::Vector3d& f) noexcept override {
    if (forces.size() < forces.capacity()) forces.push_back({t_, f.norm()});
  }
  std::vector<std::pair<double, double>> forces;  // (tick time [s], |force| [N])

 private:
  const devices::Clock& clock_;
  double empty_, lost_from_, lost_to_, t_ = 0;
  Rng rng_{11};
};

TEST(RtEngineLink, TenPercentEmptyReadsDoNotFaultATrial) {
  const auto m = test::TexturedMaterial();
  renderer::RenderOptions ro;
  renderer::HybridRenderer r(m, ro);
  devices::VirtualClock clock;
  FlakyLink dev(clock, 0.10, -1, 0);
  EngineOptions eo;
  eo.virtual_clock = &clock;
  RtEngine engine(r, dev, nullptr, eo);
  engine.Start();
  {
    test::NoAllocGuard guard;  // the virtual clock steps the same allocation-free ticks
    EXPECT_TRUE(engine.AdvanceTo(2.0));
    EXPECT_EQ(guard.count(), 0u);
  }
  engine.Stop();
  const auto st = engine.Stats();
  EXPECT_EQ(st.force_ticks, 2000u);
  EXPECT_EQ(st.vibration_ticks, 20000u);
  EXPECT_FALSE(engine.watchdog().tripped());
  EXPECT_GT(st.empty_reads, 150u);
  EXPECT_LT(st.empty_reads, 250u);
  EXPECT_EQ(st.lost_reads, 0u);
  // Each empty read rendered the last sample: the force never dropped (the stylus stays in;
  // the first 0.1 s is the force filter's rise).
  std::size_t pushing = 0, ticks = 0;
  for (const auto& [t, f] : dev.forces)
    if (t >= 0.1) ++ticks, pushing += f > 0.05;
  EXPECT_GT(ticks, 1800u);
  EXPECT_EQ(pushing, ticks - 1) << "all but the closing zero of Stop";
}

TEST(RtEngineLink, A50msDropoutFaultsTheTrialWithZeroForceFromItsFirstTick) {
  const auto m = test::TexturedMaterial();
  renderer::RenderOptions ro;
  ro.vibration = false;
  renderer::HybridRenderer r(m, ro);
  devices::VirtualClock clock;
  FlakyLink dev(clock, 0.0, 0.3, 0.05);
  EngineOptions eo;
  eo.virtual_clock = &clock;
  RtEngine engine(r, dev, nullptr, eo);
  engine.RunFor(std::chrono::seconds(1));
  EXPECT_TRUE(engine.watchdog().tripped());
  EXPECT_GE(engine.watchdog().count(FaultKind::kDisconnect), 1u);
  FaultEvent e;
  ASSERT_TRUE(engine.watchdog().PopEvent(&e));
  EXPECT_EQ(e.kind, FaultKind::kDisconnect);
  EXPECT_NEAR(e.t_s, 0.3 + 0.009, 1.5e-3) << "the tenth lost read";
  bool before = true;
  for (const auto& [t, f] : dev.forces) {
    if (t < 0.3 - 1e-9) {
      if (t >= 0.1) before = before && f > 0.05;
    } else {
      EXPECT_EQ(f, 0.0) << "at " << t << " s";
    }
  }
  EXPECT_TRUE(before) << "the stylus pushed before the dropout";
  EXPECT_GT(dev.forces.back().first, 0.3);
  EXPECT_LT(engine.Stats().force_ticks, 320u) << "a disconnect ends the run";
}

// Issue #33: a vibration model that runs away (a neural model with a pole at radius 1.05) is
// muted by the renderer and is a real-time fault of the trial like the others: the watchdog
// trips, counts it and queues its event, the tick after it commands zero force; nothing is
// allocated in the loops. The stable model (radius 0.9) plays a clean trial.
TEST(RtEngine, ARunawayVibrationModelFaultsTheTrial) {
  for (const double radius : {0.9, 1.05}) {
    const auto m = test::NeuralResonanceMaterial(radius);
    renderer::HybridRenderer r(m, renderer::RenderOptions{});
    devices::VirtualClock clock;
    FlakyLink dev(clock, 0.0, 1e9, 0.0);  // never lost
    EngineOptions eo;
    eo.virtual_clock = &clock;
    RtEngine engine(r, dev, nullptr, eo);
    engine.Start();
    {
      test::NoAllocGuard guard;
      engine.AdvanceTo(1.0);
      EXPECT_EQ(guard.count(), 0u);
    }
    engine.Stop();
    const auto st = engine.Stats();
    if (radius < 1) {
      EXPECT_FALSE(engine.watchdog().tripped());
      EXPECT_EQ(st.vibration_faults, 0u);
      continue;
    }
    EXPECT_TRUE(engine.watchdog().tripped());
    EXPECT_EQ(st.vibration_faults, 1u);
    EXPECT_EQ(r.counters().vibration_faults.load(), 1u);
    EXPECT_TRUE(r.vibration_muted());
    FaultEvent e;
    ASSERT_TRUE(engine.watchdog().PopEvent(&e));
    EXPECT_EQ(e.kind, FaultKind::kVibrationModel);
    EXPECT_STREQ(FaultName(e.kind), "vibration-model");
    std::size_t zero_in_contact = 0;
    for (const auto& [t, f] : dev.forces) zero_in_contact += t > 0.01 && t < 0.99 && f == 0.0;
    EXPECT_GE(zero_in_contact, 1u) << "the fault tick commands zero force";
    EXPECT_LE(zero_in_contact, 2u) << "one fault (the force model restarts after it)";
  }
}

}  // namespace
}  // namespace hapticlab::runner::rt_engine_test
