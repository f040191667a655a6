// The simulated back-ends (sim/src/simulated_device.cpp): the generic device and the Falcon
// twin, each over the simulated hand, opened by name.

#include "hapticlab/sim/simulated_device.hpp"

#include <gtest/gtest.h>

#include "hapticlab/core/status.hpp"

namespace hapticlab::sim {
namespace {

TEST(SimulatedDevice, TheGenericDeviceIsTheEnginesDevice) {
  auto d = OpenSimulatedDevice("sim", DefaultSamplePoses());
  ASSERT_TRUE(d.sim);
  EXPECT_FALSE(d.falcon);
  ASSERT_NE(d.sim->device, nullptr);
  EXPECT_EQ(d.sim->device, d.sim->generic.get());
  EXPECT_EQ(d.sim->twin, nullptr);
  EXPECT_TRUE(d.sim->true_device_from_sample[1].isApprox(DefaultSamplePoses()[1]));
  EXPECT_EQ(d.sim->device->Capabilities().name, "sim");
}

TEST(SimulatedDevice, TheTwinRunsTheRealFalconBackEndAfterItsFirmwareLoads) {
  auto d = OpenSimulatedDevice("falcon-twin", DefaultSamplePoses());
  ASSERT_TRUE(d.sim);
  ASSERT_TRUE(d.falcon);
  EXPECT_EQ(d.sim->device, d.falcon.get());
  EXPECT_FALSE(d.sim->generic);  // replaced by the twin
  EXPECT_NE(d.sim->twin, nullptr);
  EXPECT_NE(d.description.find("falcon-twin"), std::string::npos);
  // The back-end reads the emulated Falcon through the loaded firmware.
  renderer::DeviceSample s;
  d.sim->clock.Set(0.001);
  EXPECT_NE(d.falcon->Read(&s), devices::ReadResult::kLost);
}

TEST(SimulatedDevice, ARealOrUnknownNameIsACallersBug) {
  EXPECT_FALSE(IsSimulatedDevice("falcon"));
  EXPECT_THROW(OpenSimulatedDevice("falcon", DefaultSamplePoses()), PreconditionError);
}

}  // namespace
}  // namespace hapticlab::sim
