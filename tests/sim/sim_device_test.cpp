// The simulated rig through the real-time engine on a virtual clock: frames (a rotated and
// translated rig renders the same sample-frame interaction as the identity rig; a rig file
// that disagrees with where the sample is touches nothing), determinism, and the truth
// physics of a real side.

#include "hapticlab/sim/sim_device.hpp"

#include <gtest/gtest.h>

#include <chrono>

#include "hapticlab/runner/rt_engine.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::sim::sim_device_test {
namespace {

struct SideRun {
  Features felt;
  std::uint64_t force_ticks = 0, contact_ticks = 0, hand_contact_ticks = 0;
};

// One 1-second virtual side of Denim (Hybrid) with the sample truly at `true_pose` in the
// device frame and the engine told (by the rig file) that it is at `rig_pose`.
SideRun RunVirtualSide(const Eigen::Isometry3d& true_pose, const Eigen::Isometry3d& rig_pose) {
  const auto set = LoadProfiles(test::DataPath("protocols/profiles.toml"));
  const auto model = PlaceholderModel(set.profiles.at("Denim"));
  renderer::RenderOptions ro;
  renderer::HybridRenderer r(model, ro);
  Hand hand;
  devices::VirtualClock clock;
  SimDevice dev(SimDeviceModel{.encoder_resolution_m = 0}, hand, &clock);
  SimActuator act(hand, ro.vibration_rate_hz);
  Rng rng(7);
  hand.Begin(DrawStroke(rng), true_pose,
             model.contact.layer_thickness_m + model.geometry->max_m() - model.geometry->min_m(),
             model.contact.texture.K + 0.5 * ro.device_max_stiffness_N_per_m, nullptr,
             ro.force_rate_hz, ro.vibration_rate_hz);
  runner::EngineOptions eo;
  eo.virtual_clock = &clock;
  eo.sample_from_device = rig_pose.inverse();
  runner::RtEngine engine(r, dev, &act, eo);
  engine.RunFor(std::chrono::seconds(1));
  const auto st = engine.Stats();
  return {hand.Finish(), st.force_ticks, st.contact_ticks, hand.contact_ticks()};
}

Eigen::Isometry3d Tilted() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.04, -0.05, 0.12);
  return T;
}

void ExpectSameFeatures(const Features& a, const Features& b) {
  EXPECT_NEAR(a.vibration, b.vibration, 1e-6);
  EXPECT_NEAR(a.fluctuation, b.fluctuation, 1e-6);
  EXPECT_NEAR(a.friction, b.friction, 1e-6);
  EXPECT_NEAR(a.stiffness, b.stiffness, 1e-6);
  EXPECT_NEAR(a.pattern, b.pattern, 1e-6);
  EXPECT_NEAR(a.mean_force_N, b.mean_force_N, 1e-6);
}

TEST(SimRig, ARotatedAndTranslatedRigFeelsLikeTheIdentityRig) {
  const auto id = RunVirtualSide(Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity());
  const auto tilted = RunVirtualSide(Tilted(), Tilted());
  EXPECT_EQ(id.force_ticks, 1000u);
  EXPECT_GT(id.contact_ticks, 500u) << "the hand pressed on the virtual surface";
  EXPECT_EQ(tilted.contact_ticks, id.contact_ticks);
  EXPECT_EQ(tilted.hand_contact_ticks, id.hand_contact_ticks);
  ExpectSameFeatures(tilted.felt, id.felt);
  // The stroke's load (0.5-2 N) was felt.
  EXPECT_GT(id.felt.mean_force_N, 0.3);
}

TEST(SimRig, ARigFileThatMissesTheSampleBy5cmTouchesNothing) {
  // The rig file puts the sample 5 cm below where it is: the hand strokes where the sample
  // is, the virtual surface is rendered 5 cm lower, out of the hand's reach.
  Eigen::Isometry3d wrong = Tilted();
  wrong.translation() -= wrong.linear().col(2) * 0.05;
  const auto run = RunVirtualSide(Tilted(), wrong);
  EXPECT_EQ(run.contact_ticks, 0u);
  EXPECT_EQ(run.hand_contact_ticks, 0u);
}

TEST(SimRig, AVirtualRunIsDeterministic) {
  const auto a = RunVirtualSide(Tilted(), Tilted());
  const auto b = RunVirtualSide(Tilted(), Tilted());
  EXPECT_EQ(a.felt.vibration, b.felt.vibration);
  EXPECT_EQ(a.felt.fluctuation, b.felt.fluctuation);
  EXPECT_EQ(a.contact_ticks, b.contact_ticks);
}

TEST(SimRig, TheHandPressesOnARealSampleWithTheStrokesLoad) {
  // A real side: the truth pushes back, the device commands nothing; the hand's force loop
  // settles on the stroke's load.
  const auto set = LoadProfiles(test::DataPath("protocols/profiles.toml"));
  TruthSample truth(set.profiles.at("Cork"), 3, 10000);
  Hand hand;
  devices::VirtualClock clock;
  SimDevice dev(SimDeviceModel{}, hand, &clock);
  Stroke s;
  s.force_N = 1.5;
  hand.Begin(s, Eigen::Isometry3d::Identity(), truth.top_m(), truth.profile().stiffness_N_per_m,
             &truth, 1000, 10000);
  renderer::DeviceSample out;
  for (int k = 1; k <= 2000; ++k) {
    clock.Set(k / 1000.0);
    ASSERT_EQ(dev.Read(&out), devices::ReadResult::kOk);
    dev.WriteForce(Eigen::Vector3d::Zero());
  }
  const auto f = hand.Finish();
  EXPECT_NEAR(f.mean_force_N, 1.5, 0.3);
  EXPECT_GT(f.friction, 0.1);
  EXPECT_GT(hand.contact_ticks(), 1500u);
}

}  // namespace
}  // namespace hapticlab::sim::sim_device_test
