// The Falcon's firmware-load state machine (devices/src/falcon_firmware.cpp) against a scripted
// fake of the bootloader (fake_falcon.hpp): the recorded control sequence, retries, the
// failing state named.

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "fake_falcon.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::devices::falcon::falcon_firmware_test {
namespace {

TEST(Falcon, FirmwareLoadFollowsTheRecordedSequence) {
  FakeFalcon usb;
  usb.drop_handshakes = 7;  // the bootloader often needs a few tries
  const auto fw = Firmware(1000);
  const auto r = LoadFirmware(usb, fw);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.attempts, 1);
  EXPECT_EQ(usb.uploaded, fw);
  // The control sequence is the recorded one.
  std::ifstream f(std::string(HL_TEST_DATA_DIR) + "/falcon/setup_sequence.txt");
  std::vector<std::pair<int, int>> want;
  std::string line;
  while (std::getline(f, line))
    if (!line.empty() && line[0] != '#') {
      std::istringstream s(line);
      int a, b;
      s >> a >> b;
      want.emplace_back(a, b);
    }
  EXPECT_EQ(usb.controls, want);
  const std::vector<LoadState> trace = {
      LoadState::kPurge,  LoadState::kLineSetup,  LoadState::kHandshake, LoadState::kBootloader,
      LoadState::kUpload, LoadState::kNormalMode, LoadState::kVerify,    LoadState::kDone};
  EXPECT_EQ(r.trace, trace);
}

TEST(Falcon, FirmwareLoadRetriesAndNamesTheFailingState) {
  {
    FakeFalcon usb;
    usb.corrupt_echo_at = 500;  // line noise in the first attempt
    const auto r = LoadFirmware(usb, Firmware(1000));
    EXPECT_TRUE(r.ok) << r.error;
    EXPECT_EQ(r.attempts, 2);
  }
  {
    FakeFalcon usb;
    usb.dead = true;  // unpowered: the bootloader never answers
    const auto r = LoadFirmware(usb, Firmware(100), {.attempts = 2, .handshake_tries = 5});
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(r.attempts, 2);
    EXPECT_EQ(r.failed_in, LoadState::kHandshake);
    EXPECT_NE(r.error.find("bootloader handshake"), std::string::npos) << r.error;
    EXPECT_NE(r.error.find("after 2 attempts"), std::string::npos) << r.error;
  }
  {
    FakeFalcon usb;
    usb.firmware_runs = false;  // wrong firmware: loads, then never speaks
    const auto r = LoadFirmware(usb, Firmware(100), {.attempts = 1, .verify_tries = 4});
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(r.failed_in, LoadState::kVerify);
  }
  test::TempDir dir;
  EXPECT_THROW(ReadFirmwareFile(dir.File("missing.bin")), InputError);
}

}  // namespace
}  // namespace hapticlab::devices::falcon::falcon_firmware_test
