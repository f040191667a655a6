// The watchdog: each fault injected into a healthy stream of ticks gives zero force on that
// very tick, latches the trial as faulted, and queues one event; recovery restores the force.
// A short loss of the link zeroes the force without faulting; a sustained one is a disconnect.

#include "hapticlab/runner/watchdog.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::watchdog_test {
namespace {

constexpr double kPeriod = 1e-3;

renderer::DeviceSample Healthy(double t) {
  renderer::DeviceSample s;
  s.state.p_m = {0.01, 0, -0.001};
  s.state.v_mps = {0.05, 0, 0};
  s.t_s = t;
  return s;
}

struct Injection {
  const char* name;
  FaultKind kind;
  // Mutates the tick's inputs.
  void (*apply)(devices::ReadResult& r, renderer::DeviceSample& s, double& late,
                Eigen::Vector3d& f);
};

TEST(Watchdog, EveryFaultZeroesTheForceOnTheSameTick) {
  const Injection inj[] = {
      {"nan position", FaultKind::kNaN,
       [](devices::ReadResult&, renderer::DeviceSample& s, double&, Eigen::Vector3d&) {
         s.state.p_m.x() = std::nan("");
       }},
      {"nan velocity", FaultKind::kNaN,
       [](devices::ReadResult&, renderer::DeviceSample& s, double&, Eigen::Vector3d&) {
         s.state.v_mps.z() = INFINITY;
       }},
      {"stale data", FaultKind::kStale,
       [](devices::ReadResult&, renderer::DeviceSample& s, double&, Eigen::Vector3d&) {
         s.t_s -= 0.02;
       }},
      {"nan command", FaultKind::kBadCommand,
       [](devices::ReadResult&, renderer::DeviceSample&, double&, Eigen::Vector3d& f) {
         f.y() = std::nan("");
       }},
      {"command above the limit", FaultKind::kBadCommand,
       [](devices::ReadResult&, renderer::DeviceSample&, double&, Eigen::Vector3d& f) {
         f = {0, 0, 50};
       }},
  };
  for (const auto& in : inj) {
    Watchdog w({.stale_after_s = 0.005, .max_consecutive_misses = 3, .max_force_N = 8});
    constexpr auto kOk = devices::ReadResult::kOk;
    const Eigen::Vector3d want(0.5, -0.2, 1.5);
    double t = 0;
    for (int k = 0; k < 100; ++k, t += kPeriod) {
      const auto f = w.Check(kOk, Healthy(t), t, 0, kPeriod, want);
      ASSERT_EQ(f, want);
    }
    ASSERT_FALSE(w.tripped());
    devices::ReadResult ok = kOk;
    auto s = Healthy(t);
    double late = 0;
    Eigen::Vector3d f = want;
    in.apply(ok, s, late, f);
    Eigen::Vector3d out;
    {
      test::NoAllocGuard guard;
      out = w.Check(ok, s, t, late, kPeriod, f);
      EXPECT_EQ(guard.count(), 0u);
    }
    EXPECT_EQ(out, Eigen::Vector3d::Zero()) << in.name;
    EXPECT_EQ(w.last(), in.kind) << in.name;
    EXPECT_TRUE(w.tripped()) << in.name;
    EXPECT_EQ(w.count(in.kind), 1u);
    FaultEvent e;
    ASSERT_TRUE(w.PopEvent(&e)) << in.name;
    EXPECT_EQ(e.kind, in.kind);
    EXPECT_EQ(e.tick, 101u);
    EXPECT_FALSE(w.PopEvent(&e));
    // Healthy again: force returns; the trial stays faulted until Reset.
    t += kPeriod;
    EXPECT_EQ(w.Check(kOk, Healthy(t), t, 0, kPeriod, want), want) << in.name;
    EXPECT_TRUE(w.tripped());
    w.Reset();
    EXPECT_FALSE(w.tripped());
  }
}

TEST(Watchdog, AShortLossZeroesTheForceASustainedOneIsADisconnect) {
  constexpr auto kOk = devices::ReadResult::kOk, kLost = devices::ReadResult::kLost,
                 kEmpty = devices::ReadResult::kNoNewData;
  Watchdog w({.max_lost_reads = 10, .max_lost_s = 0.010});
  const Eigen::Vector3d want(0.5, -0.2, 1.5);
  double t = 0;
  for (int k = 0; k < 100; ++k, t += kPeriod)
    ASSERT_EQ(w.Check(kOk, Healthy(t), t, 0, kPeriod, want), want);
  // A read with no new data renders the last sample: force as wanted, no fault.
  EXPECT_EQ(w.Check(kEmpty, Healthy(t - kPeriod), t, 0, kPeriod, want), want);
  t += kPeriod;
  EXPECT_EQ(w.Check(kOk, Healthy(t), t, 0, kPeriod, want), want);
  t += kPeriod;
  // Nine lost reads: zero force on each, no fault; the link comes back, force returns.
  for (int k = 0; k < 9; ++k, t += kPeriod) {
    EXPECT_EQ(w.Check(kLost, Healthy(t), t, 0, kPeriod, want), Eigen::Vector3d::Zero()) << k;
    EXPECT_EQ(w.last(), FaultKind::kNone);
  }
  EXPECT_FALSE(w.tripped());
  EXPECT_EQ(w.Check(kOk, Healthy(t), t, 0, kPeriod, want), want);
  EXPECT_EQ(w.lost_reads(), 9u);
  // Ten in a row: a disconnect, latched.
  for (int k = 0; k < 10; ++k) {
    t += kPeriod;
    EXPECT_EQ(w.Check(kLost, Healthy(t), t, 0, kPeriod, want), Eigen::Vector3d::Zero());
  }
  EXPECT_EQ(w.last(), FaultKind::kDisconnect);
  EXPECT_TRUE(w.tripped());
  // Time counts too: at 250 Hz (4 ms a tick) the third lost read is 12 ms after the last good one.
  Watchdog slow({.max_lost_reads = 10, .max_lost_s = 0.010});
  EXPECT_EQ(slow.Check(kOk, Healthy(1.0), 1.0, 0, 0.004, want), want);
  slow.Check(kLost, Healthy(1.0), 1.004, 0, 0.004, want);
  slow.Check(kLost, Healthy(1.0), 1.008, 0, 0.004, want);
  EXPECT_FALSE(slow.tripped());
  slow.Check(kLost, Healthy(1.0), 1.012, 0, 0.004, want);
  EXPECT_TRUE(slow.tripped());
}

TEST(Watchdog, MissedDeadlinesFaultAfterTheConfiguredRun) {
  Watchdog w({.max_consecutive_misses = 3});
  const Eigen::Vector3d want(0, 0, 1);
  double t = 0;
  // Two late ticks are tolerated; the third in a row is a fault on that tick.
  EXPECT_EQ(w.Check(devices::ReadResult::kOk, Healthy(t), t, 2.5 * kPeriod, kPeriod, want), want);
  EXPECT_EQ(w.Check(devices::ReadResult::kOk, Healthy(t), t, 2.5 * kPeriod, kPeriod, want), want);
  EXPECT_EQ(w.Check(devices::ReadResult::kOk, Healthy(t), t, 2.5 * kPeriod, kPeriod, want),
            Eigen::Vector3d::Zero());
  EXPECT_EQ(w.last(), FaultKind::kDeadlineMiss);
  // An on-time tick clears the run.
  EXPECT_EQ(w.Check(devices::ReadResult::kOk, Healthy(t), t, 0, kPeriod, want), want);
  EXPECT_EQ(w.Check(devices::ReadResult::kOk, Healthy(t), t, 2.5 * kPeriod, kPeriod, want), want);
}

TEST(Watchdog, PersistentFaultsQueueBoundedEvents) {
  Watchdog w({.event_capacity = 16});
  renderer::DeviceSample s;
  for (int k = 0; k < 5000; ++k)
    w.Check(devices::ReadResult::kLost, s, k * kPeriod, 0, kPeriod, Eigen::Vector3d::Zero());
  int events = 0;
  FaultEvent e;
  while (w.PopEvent(&e)) ++events;
  EXPECT_EQ(events, 5);  // the first faulted tick, then one per 1000 ticks
  EXPECT_EQ(w.count(FaultKind::kDisconnect),
            5000u - 9u);  // the first 9 lost reads are a short loss
}

}  // namespace
}  // namespace hapticlab::runner::watchdog_test
