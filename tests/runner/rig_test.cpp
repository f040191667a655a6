// The rig file: parsing with located errors, round trip, the frames it gives the engine, and
// the plane fit of `hapticlab rig calibrate`.

#include "hapticlab/runner/rig.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/sim/falcon_twin.hpp"

namespace hapticlab::runner::rig_test {
namespace {

TEST(Rig, RoundTripsAndLocatesEveryProblem) {
  RigFile r = DefaultRig("falcon");
  r.tip_offset_m = {0, 0, -0.02};
  r.motor_units_per_Nm = 12345;
  r.world_from_device = PoseFromAxes({0.1, 0.2, 0.3}, {0, 1, 0}, {1, 0, 0});
  const RigFile back = ParseRig(RigToToml(r), "r.toml");
  for (int s = 0; s < 2; ++s)
    EXPECT_TRUE(back.DeviceFromSample(s).isApprox(r.DeviceFromSample(s), 1e-9));
  EXPECT_EQ(back.motor_units_per_Nm, 12345);
  EXPECT_EQ(back.tip_offset_m, r.tip_offset_m);
  EXPECT_EQ(back.device, "falcon");
  EXPECT_EQ(back.sha256.size(), 64u);
  const std::string bad =
      "device = \"falcon\"\n"
      "[force]\n"
      "motor_units_per_Nm = -3\n"
      "[sample.left]\n"
      "origin_m = [0, 0]\n"
      "x_axis = [1, 0, 0]\n"
      "z_axis = [2, 0, 0]\n"
      "[sample.right]\n"
      "origin_m = [0, 0, 0]\n"
      "x_axis = [1, 0, 0]\n"
      "z_axis = [0, 0, 1]\n"
      "colour = 3\n";
  try {
    ParseRig(bad, "bad.toml");
    FAIL() << "accepted a bad rig file";
  } catch (const InputError& e) {
    std::vector<std::string> fields;
    for (const auto& d : e.diagnostics()) {
      fields.push_back(d.field);
      EXPECT_EQ(d.file, "bad.toml");
      EXPECT_GT(d.line, 0);
    }
    EXPECT_NE(std::find(fields.begin(), fields.end(), "force.motor_units_per_Nm"), fields.end());
    EXPECT_NE(std::find(fields.begin(), fields.end(), "sample.left.origin_m"), fields.end());
    EXPECT_NE(std::find(fields.begin(), fields.end(), "sample.right.colour"), fields.end());
  }
  // Parallel axes are refused by name.
  const std::string parallel =
      RigToToml(DefaultRig("sim"))
          .replace(RigToToml(DefaultRig("sim")).rfind("z_axis = [0, 0, 1]"), 18,
                   "z_axis = [1, 0, 0]");
  EXPECT_THROW(ParseRig(parallel, "p.toml"), InputError);
}

TEST(Rig, TheTipOffsetAndTheDevicePoseMoveTheSampleFrame) {
  RigFile r = DefaultRig("sim");
  r.tip_offset_m = {0, 0, -0.03};  // the tip 3 cm below the reported point
  // A reported point 3 cm above the left sample's origin puts the tip on it.
  const Eigen::Vector3d reported =
      r.world_from_sample[0].translation() + Eigen::Vector3d(0, 0, 0.03);
  EXPECT_LT((r.DeviceFromSample(0).inverse() * reported).norm(), 1e-12);
  // Moving the device in the world moves the samples the other way in the device frame.
  r.world_from_device.translation() = Eigen::Vector3d(0.1, 0, 0);
  EXPECT_NEAR((r.DeviceFromSample(0).inverse() * (reported - Eigen::Vector3d(0.1, 0, 0))).norm(), 0,
              1e-12);
}

TEST(Rig, TheFalconsRestPoseIsOutOfContactOnTheBuiltInRig) {
  const RigFile r = DefaultRig("falcon");
  for (int s = 0; s < 2; ++s) {
    const Eigen::Vector3d p = r.DeviceFromSample(s).inverse() * sim::FalconHomePosition();
    EXPECT_GT(p.z(), 0.03) << "side " << s << ": the grip rests well above the sample";
  }
}

TEST(Rig, CalibrateRecoversATiltedPlaneFromNoisyTouches) {
  // A sample tilted 12 degrees about a skew axis, 4 cm below the Falcon's workspace centre;
  // eight touches with 0.2 mm noise (a stylus on a textured surface).
  const Eigen::Vector3d n =
      (Eigen::AngleAxisd(12 * std::numbers::pi / 180, Eigen::Vector3d(1, 0, 1).normalized()) *
       Eigen::Vector3d(0, 1, 0))
          .normalized();
  const Eigen::Isometry3d truth = PoseFromAxes({0.02, -0.04, 0.12}, {1, 0, 0}, n);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0, 0.2e-3);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  std::vector<Eigen::Vector3d> touches;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d local(u(rng), u(rng), noise(rng));
    touches.push_back(truth * local);
  }
  const PlaneFit f = FitSamplePlane(touches, Eigen::Vector3d(0, 1, 0));
  const Eigen::Vector3d fn = f.device_from_sample.linear().col(2);
  const double angle_deg = std::acos(std::clamp(fn.dot(n), -1.0, 1.0)) * 180 / std::numbers::pi;
  EXPECT_LT(angle_deg, 1.0);
  // The fitted surface passes within 0.5 mm of the true one (at the fitted origin).
  EXPECT_LT(std::abs((f.device_from_sample.translation() - truth.translation()).dot(n)), 0.5e-3);
  EXPECT_GT(f.rms_residual_m, 0.05e-3);
  EXPECT_LT(f.rms_residual_m, 0.4e-3);
  // +z follows the up hint; too few or collinear touches are refused.
  EXPECT_LT(
      FitSamplePlane(touches, Eigen::Vector3d(0, -1, 0)).device_from_sample.linear().col(2).dot(n),
      0);
  EXPECT_THROW(FitSamplePlane({touches[0], touches[1]}, n), InputError);
  EXPECT_THROW(FitSamplePlane({{0, 0, 0}, {0.01, 0, 0}, {0.02, 0, 0}}, n), InputError);
  EXPECT_THROW(PoseFromAxes({0, 0, 0}, {0, 0, 1}, {0, 0, 2}), PreconditionError);
}

}  // namespace
}  // namespace hapticlab::runner::rig_test
