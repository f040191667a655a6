// The Falcon twin (sim/src/falcon_twin.cpp), driven through the real Falcon back-end's
// packet codec, kinematics and firmware loader (devices/src/falcon.cpp): the loader's whole
// protocol is answered, the status packets carry the encoder counts of where the hand holds
// the grip (read back by the back-end's forward kinematics), a motor effort reaches the hand
// as the force the back-end meant (its ForceToTorque, inverted by the twin), and the link's
// faults happen as configured.

#include "hapticlab/sim/falcon_twin.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>

#include "hapticlab/devices/clock.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/sim/sim_device.hpp"
#include "hapticlab/sim/sim_lab.hpp"

namespace hapticlab::sim::falcon_twin_test {
namespace {

namespace fal = devices::falcon;

// A hand holding the grip at the Falcon's home pose (the sample's top there), not stroking.
struct Rig {
  devices::VirtualClock clock;
  Hand hand;
  FalconTwinTransport twin;
  explicit Rig(const FalconTwinOptions& o = {}) : twin(hand, clock, o) {
    Eigen::Isometry3d at_home = Eigen::Isometry3d::Identity();
    at_home.translation() = FalconHomePosition();
    hand.Begin(Stroke{.speed_mps = 1e-9, .force_N = 0, .length_m = 1e-9}, at_home, 0, 1000, nullptr,
               1000, 10000);
  }
  void Load() {
    const auto r = fal::LoadFirmware(twin, FalconTwinFirmware());
    ASSERT_TRUE(r.ok) << r.error;
    twin.BeginRun();
  }
  // One servo tick: the command out, then a read of what came back.
  bool Exchange(const fal::Command& c, fal::Status* s) {
    clock.Set(clock.Now() + 1e-3);
    const auto p = fal::EncodeCommand(c);
    if (twin.BulkWrite(p.data(), 16, 10) != 16) return false;
    std::array<std::uint8_t, 64> in{};
    const int n = twin.BulkRead(in.data(), 64, 10);
    return n > 2 && fal::DecodeStatus(in.data() + 2, static_cast<std::size_t>(n - 2), s);
  }
  // The command the back-end sends for force f at the grip at home (effort = -tau * scale).
  static fal::Command ForceCommand(const Eigen::Vector3d& f_N) {
    Eigen::Vector3d tau;
    EXPECT_TRUE(fal::ForceToTorque(FalconHomePosition(), f_N, &tau));
    fal::Command c;
    for (int k = 0; k < 3; ++k)
      c.motor[static_cast<std::size_t>(k)] =
          static_cast<std::int16_t>(std::lround(-tau[k] * FalconTwinOptions{}.motor_units_per_Nm));
    return c;
  }
};

TEST(FalconTwin, TheBackEndsLoaderLoadsItsFirmware) {
  Rig r;
  EXPECT_FALSE(r.twin.firmware_loaded());
  r.Load();
  EXPECT_TRUE(r.twin.firmware_loaded());
  EXPECT_GT(r.twin.status_packets(), 0u);
}

TEST(FalconTwin, StatusEncodersAreWhereTheHandHoldsTheGrip) {
  Rig r;
  r.Load();
  fal::Status s;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(r.Exchange({}, &s)) << i;
  Eigen::Vector3d theta, p;
  for (int k = 0; k < 3; ++k)
    theta[k] = fal::EncoderToAngle(s.encoder[static_cast<std::size_t>(k)]);
  ASSERT_TRUE(fal::ForwardKinematics(theta, FalconHomePosition(), &p));
  const Eigen::Vector3d held = FalconHomePosition() + r.hand.p_sample_m();
  // Within the encoders' quantization (about 0.1 mm at the grip).
  EXPECT_LT((p - held).norm(), 2e-4) << p.transpose() << " vs " << held.transpose();
  EXPECT_LT((p - FalconHomePosition()).norm(), 5e-3);
}

TEST(FalconTwin, AMotorEffortIsFeltAsTheForceTheBackEndMeant) {
  // The hand counts a tick as contact above 0.3 N pushing into the sample (+z): 0.35 N must
  // count, 0.25 N and a pull of 1 N must not (a wrong sign or scale of the effort fails).
  for (const auto& [fz_N, contact] :
       {std::pair{0.35, true}, std::pair{0.25, false}, std::pair{-1.0, false}}) {
    Rig r;
    r.Load();
    fal::Status s;
    ASSERT_TRUE(r.Exchange({}, &s));  // the hand's first step: nothing felt yet
    const auto before = r.hand.contact_ticks();
    ASSERT_TRUE(r.Exchange(Rig::ForceCommand({0, 0, fz_N}), &s));
    EXPECT_EQ(r.hand.contact_ticks() - before, contact ? 1u : 0u) << fz_N << " N";
  }
}

TEST(FalconTwin, DropoutsEmptyReadsAndSplitPackets) {
  Rig r;
  r.Load();
  r.twin.InjectDropout(r.clock.Now() + 0.0005, 0.002);
  fal::Status s;
  EXPECT_FALSE(r.Exchange({}, &s));  // inside the dropout
  r.clock.Set(r.clock.Now() + 0.0001);
  std::uint8_t buf[64];
  EXPECT_LT(r.twin.BulkRead(buf, 64, 10), 0);
  EXPECT_LT(r.twin.Control(fal::ftdi::kRequestType, fal::ftdi::kReset, fal::ftdi::kPurgeRx, 0, 10),
            0);
  r.clock.Set(r.clock.Now() + 0.003);
  EXPECT_TRUE(r.Exchange({}, &s));  // over

  // Half the reads empty (the loader retries through them), counted as such.
  Rig empty({.empty_read_probability = 0.5, .seed = 4});
  empty.Load();
  const auto p = fal::EncodeCommand({});
  const auto empty_before = empty.twin.empty_reads();
  int empties = 0;
  for (int i = 0; i < 200; ++i) {
    ASSERT_EQ(empty.twin.BulkWrite(p.data(), 16, 10), 16);
    const int n = empty.twin.BulkRead(buf, 64, 10);
    ASSERT_GE(n, 2);
    empties += n == 2 ? 1 : 0;  // modem status bytes only
  }
  EXPECT_EQ(empty.twin.empty_reads() - empty_before, static_cast<std::uint64_t>(empties));
  EXPECT_GT(empties, 60);
  EXPECT_LT(empties, 140);

  Rig split({.split_probability = 1});
  split.Load();
  while (split.twin.BulkRead(buf, 64, 10) > 2) {
  }  // what the loader left unread
  const auto before = split.twin.split_packets();
  ASSERT_EQ(split.twin.BulkWrite(p.data(), 16, 10), 16);
  EXPECT_EQ(split.twin.BulkRead(buf, 64, 10), 2 + 7);  // the packet's first 7 bytes
  EXPECT_EQ(split.twin.split_packets(), before + 1);
  EXPECT_EQ(split.twin.BulkRead(buf, 64, 10), 2 + 9);  // the rest with the next read
  EXPECT_EQ(buf[2 + 8], '>');
}

}  // namespace
}  // namespace hapticlab::sim::falcon_twin_test
