// The watchdog: each fault injected into a healthy stream of ticks gives zero force on that
// very tick, latches the trial as faulted, and queues one event; recovery restores the force.

#include "hapticlab/runner/watchdog.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner {
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
  void (*apply)(bool& ok, renderer::DeviceSample& s, double& late, Eigen::Vector3d& f);
};

TEST(Watchdog, EveryFaultZeroesTheForceOnTheSameTick) {
  const Injection inj[] = {
      {"disconnect", FaultKind::kDisconnect, [](bool& ok, renderer::DeviceSample&, double&, Eigen::Vector3d&) { ok = false; }},
      {"nan position", FaultKind::kNaN,
       [](bool&, renderer::DeviceSample& s, double&, Eigen::Vector3d&) { s.state.p_m.x() = std::nan(""); }},
      {"nan velocity", FaultKind::kNaN,
       [](bool&, renderer::DeviceSample& s, double&, Eigen::Vector3d&) { s.state.v_mps.z() = INFINITY; }},
      {"stale data", FaultKind::kStale, [](bool&, renderer::DeviceSample& s, double&, Eigen::Vector3d&) { s.t_s -= 0.02; }},
      {"nan command", FaultKind::kBadCommand, [](bool&, renderer::DeviceSample&, double&, Eigen::Vector3d& f) { f.y() = std::nan(""); }},
      {"command above the limit", FaultKind::kBadCommand,
       [](bool&, renderer::DeviceSample&, double&, Eigen::Vector3d& f) { f = {0, 0, 50}; }},
  };
  for (const auto& in : inj) {
    Watchdog w({.stale_after_s = 0.005, .max_consecutive_misses = 3, .max_force_N = 8});
    const Eigen::Vector3d want(0.5, -0.2, 1.5);
    double t = 0;
    for (int k = 0; k < 100; ++k, t += kPeriod) {
      const auto f = w.Check(true, Healthy(t), t, 0, kPeriod, want);
      ASSERT_EQ(f, want);
    }
    ASSERT_FALSE(w.tripped());
    bool ok = true;
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
    EXPECT_EQ(w.Check(true, Healthy(t), t, 0, kPeriod, want), want) << in.name;
    EXPECT_TRUE(w.tripped());
    w.Reset();
    EXPECT_FALSE(w.tripped());
  }
}

TEST(Watchdog, MissedDeadlinesFaultAfterTheConfiguredRun) {
  Watchdog w({.max_consecutive_misses = 3});
  const Eigen::Vector3d want(0, 0, 1);
  double t = 0;
  // Two late ticks are tolerated; the third in a row is a fault on that tick.
  EXPECT_EQ(w.Check(true, Healthy(t), t, 2.5 * kPeriod, kPeriod, want), want);
  EXPECT_EQ(w.Check(true, Healthy(t), t, 2.5 * kPeriod, kPeriod, want), want);
  EXPECT_EQ(w.Check(true, Healthy(t), t, 2.5 * kPeriod, kPeriod, want), Eigen::Vector3d::Zero());
  EXPECT_EQ(w.last(), FaultKind::kDeadlineMiss);
  // An on-time tick clears the run.
  EXPECT_EQ(w.Check(true, Healthy(t), t, 0, kPeriod, want), want);
  EXPECT_EQ(w.Check(true, Healthy(t), t, 2.5 * kPeriod, kPeriod, want), want);
}

TEST(Watchdog, PersistentFaultsQueueBoundedEvents) {
  Watchdog w({.event_capacity = 16});
  renderer::DeviceSample s;
  for (int k = 0; k < 5000; ++k) w.Check(false, s, k * kPeriod, 0, kPeriod, Eigen::Vector3d::Zero());
  int events = 0;
  FaultEvent e;
  while (w.PopEvent(&e)) ++events;
  EXPECT_EQ(events, 5);  // the first tick, then one per 1000 ticks
  EXPECT_EQ(w.count(FaultKind::kDisconnect), 5000u);
}

}  // namespace
}  // namespace hapticlab::runner
