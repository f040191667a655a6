// The Force Dimension back-end (devices/src/dhd.cpp) against a scripted DHD SDK
// (fake_sdk/dhdc.h; the SDK is not a Debian package, so CI never has it): the SDK's own
// message when no device opens, the device closed again when forces cannot be enabled,
// positions and velocities passed through in SI units on the device's id, a failed read
// reported as lost, and zero force commanded before the device is closed.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <stdexcept>
#include <string>

#include "dhdc.h"
#include "hapticlab/devices/vendor.hpp"

namespace hapticlab::devices::dhd_test {
namespace {

std::string ErrorOf(const auto& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(nothing thrown)";
}

TEST(Dhd, OpenFailuresCarryTheSdksMessageAndCloseTheDevice) {
  EXPECT_TRUE(HaveDhd());
  fake_dhd::state = {};
  fake_dhd::state.open_result = -1;
  fake_dhd::state.last_error = "no device found";
  EXPECT_EQ(ErrorOf([] { (void)OpenDhd(); }), "dhd: cannot open a device: no device found");
  EXPECT_EQ(fake_dhd::state.close_calls, 0);
  fake_dhd::state = {};
  fake_dhd::state.open_result = 2;
  fake_dhd::state.enable_result = -1;
  fake_dhd::state.last_error = "device busy";
  EXPECT_EQ(ErrorOf([] { (void)OpenDhd(); }), "dhd: cannot enable forces: device busy");
  EXPECT_EQ(fake_dhd::state.close_calls, 1);
  EXPECT_EQ(fake_dhd::state.last_id, static_cast<char>(2));
}

TEST(Dhd, ReadsWritesAndShutsDownOnItsDevice) {
  fake_dhd::state = {};
  fake_dhd::state.open_result = 3;
  fake_dhd::state.system_name = "sigma.7";
  {
    auto d = OpenDhd();
    EXPECT_EQ(fake_dhd::state.enable_calls, 1);
    EXPECT_EQ(d->Capabilities().name, "dhd sigma.7");
    fake_dhd::state.p_m[0] = 0.01, fake_dhd::state.p_m[1] = -0.02, fake_dhd::state.p_m[2] = 0.03;
    fake_dhd::state.v_mps[2] = -0.5;
    DeviceSample s;
    fake_dhd::state.last_id = -2;
    ASSERT_EQ(d->Read(&s), ReadResult::kOk);
    EXPECT_EQ(fake_dhd::state.last_id, static_cast<char>(3));    // its own device
    EXPECT_EQ(s.state.p_m, Eigen::Vector3d(0.01, -0.02, 0.03));  // metres, as the SDK's
    EXPECT_EQ(s.state.v_mps, Eigen::Vector3d(0, 0, -0.5));
    EXPECT_GE(s.t_s, 0);
    fake_dhd::state.read_result = -1;
    EXPECT_EQ(d->Read(&s), ReadResult::kLost);
    d->WriteForce({1.5, -2, 0.25});
    EXPECT_EQ(fake_dhd::state.force_N[0], 1.5);
    EXPECT_EQ(fake_dhd::state.force_N[1], -2);
    EXPECT_EQ(fake_dhd::state.force_N[2], 0.25);
    EXPECT_EQ(fake_dhd::state.last_id, static_cast<char>(3));
    EXPECT_EQ(fake_dhd::state.close_calls, 0);
  }
  // Closing: zero force first, then the device.
  EXPECT_EQ(fake_dhd::state.force_N[0], 0);
  EXPECT_EQ(fake_dhd::state.force_N[1], 0);
  EXPECT_EQ(fake_dhd::state.force_N[2], 0);
  EXPECT_EQ(fake_dhd::state.close_calls, 1);
}

}  // namespace
}  // namespace hapticlab::devices::dhd_test
