#include "hapticlab/renderer/hybrid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <thread>

#include "hapticlab/test/test_util.hpp"
#include "test_materials.hpp"

namespace hapticlab::renderer::hybrid_test {
namespace {

DeviceSample Sample(double x, double z, double vx, double t) {
  DeviceSample s;
  s.state.p_m = {x, 0, z};
  s.state.v_mps = {vx, 0, 0};
  s.t_s = t;
  return s;
}

TEST(Hybrid, NanOrStaleInputZeroesForceOnTheSameTick) {
  const auto m = test::TexturedMaterial();
  RenderOptions o;
  o.hybrid_filter = false;
  HybridRenderer r(m, o);
  auto cmd = r.ForceTick(Sample(0, -0.2e-3, 0.05, 0.0), 0.0);
  ASSERT_GT(cmd.force_N.norm(), 0.1);
  auto bad = Sample(0, 0.1e-3, 0.05, 0.001);
  bad.state.p_m.x() = std::numeric_limits<double>::quiet_NaN();
  cmd = r.ForceTick(bad, 0.001);
  EXPECT_TRUE(cmd.fault);
  EXPECT_EQ(cmd.force_N.norm(), 0.0);
  EXPECT_EQ(r.counters().nan_faults.load(), 1u);
  cmd = r.ForceTick(Sample(0, 0.1e-3, 0.05, 0.002), 0.002 + o.stale_after_s * 1.5);
  EXPECT_TRUE(cmd.fault);
  EXPECT_EQ(cmd.force_N.norm(), 0.0);
  EXPECT_EQ(r.counters().stale_faults.load(), 1u);
  // Good data again: force comes back.
  cmd = r.ForceTick(Sample(0, -0.2e-3, 0.05, 0.003), 0.003);
  EXPECT_FALSE(cmd.fault);
  EXPECT_GT(cmd.force_N.norm(), 0.1);
}

TEST(Hybrid, ForceNeverExceedsTheLimitNorIsNanOverAMillionRandomStates) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> pos(-5e-3, 5e-3), depth(-20e-3, 2e-3), vel(-2.0, 2.0);
  std::uniform_real_distribution<double> u01(0, 1);
  const auto base = test::TexturedMaterial();
  const ForceAlgorithm algs[] = {ForceAlgorithm::kWall, ForceAlgorithm::kNorm,
                                 ForceAlgorithm::kFric1, ForceAlgorithm::kFric2,
                                 ForceAlgorithm::kNone};
  // A million states in the release build; a tenth of them (every model, algorithm and
  // filter setting still covered) in the sanitizer builds.
  const int per_model = test::kSanitizerBuild ? 5000 : 50000;
  int states = 0;
  for (int model = 0; model < 20; ++model) {
    MaterialModel m = base;
    m.contact.texture = {std::exp(u01(rng) * 10), u01(rng) * 50, 1 + u01(rng)};
    m.contact.base = {u01(rng) < 0.5 ? 0.0 : std::exp(u01(rng) * 10), u01(rng) * 10, 1 + u01(rng)};
    m.contact.base_model = u01(rng) < 0.5 ? BaseModel::kLinear : BaseModel::kHuntCrossley;
    m.friction = {std::exp(u01(rng) * 12), u01(rng) * 2, u01(rng) * 5};
    RenderOptions o;
    o.algorithm = algs[model % 5];
    o.hybrid_filter = model % 2 == 0;
    o.max_force_N = 1 + 10 * u01(rng);
    HybridRenderer r(m, o);
    for (int k = 0; k < per_model; ++k, ++states) {
      auto s = Sample(pos(rng), depth(rng), vel(rng), k * 1e-3);
      s.state.p_m.y() = pos(rng);
      s.state.v_mps.y() = vel(rng);
      s.state.v_mps.z() = vel(rng);
      if (k % 997 == 0) s.state.v_mps.z() = std::numeric_limits<double>::infinity();
      const auto cmd = r.ForceTick(s, k * 1e-3);
      ASSERT_TRUE(cmd.force_N.allFinite());
      ASSERT_LE(cmd.force_N.norm(), o.max_force_N * (1 + 1e-12));
    }
  }
  EXPECT_EQ(states, 20 * per_model);
}

TEST(Hybrid, TicksAllocateNothing) {
  const auto m = test::TexturedMaterial();
  HybridRenderer r(m, RenderOptions{});
  test::NoAllocGuard guard;
  for (int k = 0; k < 1000; ++k) {
    r.ForceTick(Sample(k * 5e-5, 0.2e-3, 0.05, k * 1e-3), k * 1e-3);
    for (int j = 0; j < 10; ++j) r.VibrationTick();
  }
  EXPECT_EQ(guard.count(), 0u);
}

// Issue #33: an unstable vibration model (a neural model whose linear part has a pole at
// radius 1.05) is muted by the vibration tick and raised as a fault on the next force tick:
// zero force that tick, counted once; the actuator is silent from then on; nothing allocated.
// The same model with radius 0.9 plays and never faults.
TEST(Hybrid, AnUnstableVibrationModelIsMutedAndFaultsTheNextForceTick) {
  for (const double radius : {0.9, 1.05}) {
    const auto m = test::NeuralResonanceMaterial(radius);
    HybridRenderer r(m, RenderOptions{});
    std::vector<double> vib, fault_force;
    vib.reserve(20000);
    fault_force.reserve(100);
    int faults = 0, fault_tick = -1;
    {
      test::NoAllocGuard guard;
      for (int k = 0; k < 2000; ++k) {
        const auto cmd = r.ForceTick(Sample(k * 5e-5, 0.2e-3, 0.05, k * 1e-3), k * 1e-3);
        if (cmd.fault) {
          EXPECT_TRUE(cmd.vibration_fault);
          EXPECT_EQ(cmd.force_N.norm(), 0.0);
          ++faults;
          if (fault_tick < 0) fault_tick = k;
        }
        for (int j = 0; j < 10; ++j) vib.push_back(r.VibrationTick());
      }
      EXPECT_EQ(guard.count(), 0u);
    }
    double peak = 0, late = 0;
    for (std::size_t i = 0; i < vib.size(); ++i) {
      peak = std::max(peak, std::abs(vib[i]));
      if (i >= vib.size() - 2000) late = std::max(late, std::abs(vib[i]));
    }
    if (radius < 1) {
      EXPECT_EQ(faults, 0);
      EXPECT_FALSE(r.vibration_muted());
      EXPECT_GT(late, 0.05) << "the stable model plays";
    } else {
      EXPECT_EQ(faults, 1) << "one fault, on the force tick after the runaway";
      EXPECT_EQ(r.counters().vibration_faults.load(), 1u);
      EXPECT_TRUE(r.vibration_muted());
      EXPECT_GT(fault_tick, 0);
      // Never above the model's declared maximum (kNeuralMaxLevel x the band's RMS of 1, plus
      // the high-pass's overshoot), and silent after the mute.
      EXPECT_LT(peak, 2 * kNeuralMaxLevel);
      EXPECT_LT(late, 1e-9);
    }
  }
}

TEST(Hybrid, VibrationFollowsContactAndIsHighPassed) {
  const auto m = test::TexturedMaterial();
  RenderOptions o;
  HybridRenderer r(m, o);
  // Stroking at 5 cm/s in contact: vibration present and with ~zero mean (high-passed).
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int k = 0; k < 2000; ++k) {
    r.ForceTick(Sample(k * 5e-5, 0.2e-3, 0.05, k * 1e-3), k * 1e-3);
    for (int j = 0; j < 10; ++j) {
      const double a = r.VibrationTick();
      if (k > 200) {
        sum += a;
        sum2 += a * a;
        ++n;
      }
    }
  }
  const double rms = std::sqrt(sum2 / n);
  EXPECT_GT(rms, 0.1);
  EXPECT_LT(std::abs(sum / n), 0.05 * rms);
  // Lifted off: silence within a force tick (the high-pass rings out its last sample only).
  r.ForceTick(Sample(0.1, 5e-3, 0.05, 2.0), 2.0);
  double late = 0;
  for (int j = 0; j < 200; ++j) late = r.VibrationTick();
  EXPECT_LT(std::abs(late), 1e-3 * rms);
}

TEST(Hybrid, ForceAndVibrationTicksRunOnTwoThreads) {
  const auto m = test::TexturedMaterial();
  HybridRenderer r(m, RenderOptions{});
  std::atomic<bool> done{false}, started{false};
  std::thread vib([&] {
    while (!done.load()) {
      ASSERT_TRUE(std::isfinite(r.VibrationTick()));
      started = true;
    }
  });
  // On a loaded machine the thread may start late; the ticks must overlap, so wait for it.
  while (!started.load()) std::this_thread::yield();
  for (int k = 0; k < 20000; ++k) r.ForceTick(Sample(k * 5e-5, 0.2e-3, 0.05, k * 1e-3), k * 1e-3);
  done = true;
  vib.join();
  EXPECT_EQ(r.counters().force_ticks.load(), 20000u);
  EXPECT_GT(r.counters().vibration_ticks.load(), 0u);
}

}  // namespace
}  // namespace hapticlab::renderer::hybrid_test
