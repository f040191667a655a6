// The OpenHaptics back-end (devices/src/openhaptics.cpp) against a scripted HD API
// (fake_sdk/HD/hd.h; the SDK is not a Debian package, so CI never has it), its servo
// callback run tick by tick as the HD scheduler would: millimetres in, metres out; the
// nominal stiffness in N/mm reported in N/m; the engine's force sent while fresh and zero
// once older than the 5 ms stale limit; a device error reported as a lost read; the
// scheduler stopped and the device disabled on close.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include "HD/hd.h"
#include "hapticlab/devices/vendor.hpp"

namespace hapticlab::devices::openhaptics_test {
namespace {

TEST(OpenHaptics, AnInitialisationErrorIsReportedWithItsCode) {
  EXPECT_TRUE(HaveOpenHaptics());
  fake_hd::state = {};
  fake_hd::state.init_error = 0x0301;
  try {
    (void)OpenOpenHaptics("Phantom 1");
    ADD_FAILURE() << "a failed initialisation was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("error " + std::to_string(0x0301)), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(fake_hd::state.init_name, "Phantom 1");
  fake_hd::state = {};
  (void)OpenOpenHaptics();
  EXPECT_EQ(fake_hd::state.init_name, "(default)");
}

TEST(OpenHaptics, MillimetresInMetresOutAndStiffnessInNewtonsPerMetre) {
  fake_hd::state = {};
  auto d = OpenOpenHaptics();
  EXPECT_TRUE(fake_hd::state.force_output);
  EXPECT_TRUE(fake_hd::state.scheduler_running);
  const auto caps = d->Capabilities();
  EXPECT_DOUBLE_EQ(caps.max_stiffness_N_per_m, 800);  // 0.8 N/mm
  EXPECT_DOUBLE_EQ(caps.max_force_N, 3.3);
  DeviceSample s;
  EXPECT_EQ(d->Read(&s), ReadResult::kLost);  // no servo tick yet
  fake_hd::state.p_mm[0] = 10, fake_hd::state.p_mm[1] = -20, fake_hd::state.p_mm[2] = 30;
  fake_hd::state.v_mmps[0] = 100;
  EXPECT_EQ(fake_hd::Tick(), HD_CALLBACK_CONTINUE);
  ASSERT_EQ(d->Read(&s), ReadResult::kOk);
  EXPECT_TRUE(s.state.p_m.isApprox(Eigen::Vector3d(0.01, -0.02, 0.03), 1e-12));
  EXPECT_TRUE(s.state.v_mps.isApprox(Eigen::Vector3d(0.1, 0, 0), 1e-12));
  EXPECT_EQ(d->Read(&s), ReadResult::kNoNewData);  // the servo has not run since
  fake_hd::state.frame_error = 0x0200;
  fake_hd::Tick();
  EXPECT_EQ(d->Read(&s), ReadResult::kLost);
  d.reset();
  EXPECT_FALSE(fake_hd::state.scheduler_running);
  EXPECT_TRUE(fake_hd::state.disabled);
  EXPECT_EQ(fake_hd::state.callback, nullptr);
}

TEST(OpenHaptics, TheEnginesForceGoesOutWhileFreshAndZeroOnceStale) {
  fake_hd::state = {};
  auto d = OpenOpenHaptics();
  const Eigen::Vector3d f(1, -2, 0.5);
  // Fresh: a servo tick right after the write sends it (retried in case this thread was
  // descheduled for more than 5 ms between the two calls).
  bool sent = false;
  for (int i = 0; i < 50 && !sent; ++i) {
    d->WriteForce(f);
    fake_hd::Tick();
    sent = Eigen::Vector3d(fake_hd::state.force_N[0], fake_hd::state.force_N[1],
                           fake_hd::state.force_N[2]) == f;
  }
  EXPECT_TRUE(sent);
  // Stale: more than 5 ms after the engine's last write, the servo commands zero.
  std::this_thread::sleep_for(std::chrono::milliseconds(6));
  fake_hd::Tick();
  EXPECT_EQ(fake_hd::state.force_N[0], 0);
  EXPECT_EQ(fake_hd::state.force_N[1], 0);
  EXPECT_EQ(fake_hd::state.force_N[2], 0);
}

}  // namespace
}  // namespace hapticlab::devices::openhaptics_test
