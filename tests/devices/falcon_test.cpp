// The Falcon back-end without a device (devices/src/falcon.cpp): packets against fixtures,
// kinematics, and the HapticDevice on a scripted fake of the link (fake_falcon.hpp). The
// firmware-load state machine: falcon_firmware_test.cpp.

#include "hapticlab/devices/falcon.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <sstream>
#include <utility>

#include "fake_falcon.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::devices::falcon::falcon_test {
namespace {

std::vector<std::uint8_t> Hex(const std::string& path) {
  std::ifstream f(path);
  std::vector<std::uint8_t> out;
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    std::string b;
    while (s >> b) out.push_back(static_cast<std::uint8_t>(std::stoi(b, nullptr, 16)));
  }
  return out;
}

TEST(Falcon, PacketsEncodeAndDecodeAgainstFixtures) {
  Command c;
  c.motor = {291, -2, -32768};
  c.leds = 0x04;
  c.homing = true;
  const auto p = EncodeCommand(c);
  const std::uint8_t want[16] = {'<',  0x44, 0x43, 0x42, 0x41, 0x4f, 0x50, 0x50,
                                 0x50, 0x41, 0x41, 0x41, 0x49, 0x46, 0x41, '>'};
  EXPECT_EQ(std::memcmp(p.data(), want, 16), 0);
  const auto stream = Hex(std::string(HL_TEST_DATA_DIR) + "/falcon/status_stream.hex");
  ASSERT_EQ(stream.size(), 52u);
  Status st;
  int malformed = 0;
  ASSERT_TRUE(DecodeStatus(stream.data(), stream.size(), &st, &malformed));
  EXPECT_EQ(st.encoder[0], 291);
  EXPECT_EQ(st.encoder[1], -2);
  EXPECT_EQ(st.encoder[2], -32768);
  EXPECT_EQ(st.homing, 0b101 & 0x7);
  EXPECT_EQ(st.buttons, 0b0011);
  EXPECT_EQ(malformed, 1);
  EXPECT_FALSE(DecodeStatus(stream.data(), 20, &st));  // only the broken ones
}

TEST(Falcon, KinematicsRoundTripAndVirtualWork) {
  EXPECT_NEAR(EncoderToAngle(0), 35.0 * 3.14159265358979 / 180, 1e-12);
  int checked = 0;
  for (double x = -0.03; x <= 0.03 + 1e-9; x += 0.015)
    for (double y = -0.03; y <= 0.03 + 1e-9; y += 0.015)
      for (double z = 0.11; z <= 0.15 + 1e-9; z += 0.01) {
        const Eigen::Vector3d p(x, y, z);
        Eigen::Vector3d th, back;
        ASSERT_TRUE(InverseKinematics(p, &th)) << p.transpose();
        ASSERT_TRUE(ForwardKinematics(th, Eigen::Vector3d(0, 0, 0.13), &back)) << p.transpose();
        EXPECT_LT((back - p).norm(), 1e-8) << p.transpose();
        // tau . dtheta = f . dp for a small displacement.
        const Eigen::Vector3d f(1.0, -2.0, 0.5), dp(1e-6, 2e-6, -1e-6);
        Eigen::Vector3d tau, th2;
        ASSERT_TRUE(ForceToTorque(p, f, &tau));
        ASSERT_TRUE(InverseKinematics(p + dp, &th2));
        EXPECT_NEAR(tau.dot(th2 - th), f.dot(dp), 1e-3 * std::abs(f.dot(dp)));
        ++checked;
      }
  EXPECT_EQ(checked, 125);
  Eigen::Vector3d th;
  EXPECT_FALSE(InverseKinematics(Eigen::Vector3d(0.5, 0, 0.13), &th));  // far outside
}

TEST(Falcon, DeviceReadsPositionsAndCommandsTorques) {
  auto fake = std::make_unique<FakeFalcon>();
  FakeFalcon* usb = fake.get();
  usb->drop_handshakes = 0;
  ASSERT_TRUE(LoadFirmware(*usb, Firmware(64)).ok);
  usb->motors.clear();
  // Encoders of a known position (quantized): the device must report the FK of those angles.
  const Eigen::Vector3d p0(0.01, -0.02, 0.125);
  Eigen::Vector3d th;
  ASSERT_TRUE(InverseKinematics(p0, &th));
  const double per_count = EncoderToAngle(1) - EncoderToAngle(0);
  for (int k = 0; k < 3; ++k)
    usb->encoders[static_cast<std::size_t>(k)] =
        static_cast<std::int16_t>(std::lround((th[k] - EncoderToAngle(0)) / per_count));
  double t = 0;
  FalconDevice dev(std::move(fake), [&] { return t; });
  DeviceSample s;
  ASSERT_EQ(dev.Read(&s), ReadResult::kOk);
  EXPECT_LT((s.state.p_m - p0).norm(), 2e-4) << "within the encoder quantization";
  const Eigen::Vector3d q(EncoderToAngle(usb->encoders[0]), EncoderToAngle(usb->encoders[1]),
                          EncoderToAngle(usb->encoders[2]));
  Eigen::Vector3d fk;
  ASSERT_TRUE(ForwardKinematics(q, p0, &fk));
  EXPECT_LT((s.state.p_m - fk).norm(), 1e-9);
  // A force command becomes motor efforts -J^-T f * scale on the next exchange.
  dev.WriteForce(Eigen::Vector3d(0, 0, 2.0));
  t = 0.001;
  ASSERT_EQ(dev.Read(&s), ReadResult::kOk);
  Eigen::Vector3d tau;
  ASSERT_TRUE(ForceToTorque(s.state.p_m, Eigen::Vector3d(0, 0, 2.0), &tau));
  ASSERT_EQ(usb->motors.size(), 2u);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(usb->motors[1][static_cast<std::size_t>(k)], -tau[k] * 10000, 1.0);
  // Non-finite force: zero effort.
  dev.WriteForce(Eigen::Vector3d(std::nan(""), 0, 0));
  ASSERT_EQ(dev.Read(&s), ReadResult::kOk);
  EXPECT_EQ(usb->motors.back(), (std::array<std::int16_t, 3>{0, 0, 0}));
  // Firmware gone: the link answers with modem status only, reads carry no new data.
  usb->firmware_runs = false;
  for (int k = 0; k < 5; ++k) EXPECT_EQ(dev.Read(&s), ReadResult::kNoNewData);
  EXPECT_EQ(dev.empty_reads(), 5u);
  EXPECT_EQ(dev.packets(), 3u);
  // Unplugged: the exchange fails.
  usb->unplugged = true;
  EXPECT_EQ(dev.Read(&s), ReadResult::kLost);
  EXPECT_EQ(dev.lost_reads(), 1u);
  EXPECT_EQ(dev.Capabilities().name, "falcon");
}

TEST(Falcon, APacketSplitAcrossTwoReadsIsReassembled) {
  auto fake = std::make_unique<FakeFalcon>();
  FakeFalcon* usb = fake.get();
  usb->drop_handshakes = 0;
  ASSERT_TRUE(LoadFirmware(*usb, Firmware(64)).ok);
  usb->encoders = {120, -340, 55};
  double t = 0;
  FalconDevice dev(std::move(fake), [&] { return t; });
  DeviceSample s;
  // Each status packet arrives in two USB reads: 7 bytes, then 9.
  usb->split_replies_at = 7;
  ASSERT_EQ(dev.Read(&s), ReadResult::kNoNewData) << "the first half alone is no packet";
  t = 0.001;
  ASSERT_EQ(dev.Read(&s), ReadResult::kOk) << "the second half completes it";
  EXPECT_EQ(dev.last_status().encoder, (std::array<std::int16_t, 3>{120, -340, 55}));
  EXPECT_EQ(dev.malformed_packets(), 0);
  EXPECT_EQ(dev.packets(), 1u);
}

}  // namespace
}  // namespace hapticlab::devices::falcon::falcon_test
