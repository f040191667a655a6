// hapticlab device list / falcon-load through the command line (apps/hapticlab/cmd_device.cpp),
// on a machine with or without the lab's hardware: nothing here needs a device.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_device_test {
namespace {

std::string Cli() { return HL_CLI_PATH; }

// device list: the JSON schema, and the text form saying the same counts.
TEST(DeviceCli, ListGivesTheSameInventoryAsJsonAndAsText) {
  std::string out;
  ASSERT_EQ(test::RunCommand("{ " + Cli() + " device list --json 2>/dev/null; }", &out), 0) << out;
  const auto j = nlohmann::json::parse(out);
  ASSERT_TRUE(j["falcons"].is_number_integer()) << out;
  EXPECT_GE(j["falcons"].get<int>(), 0);
  ASSERT_TRUE(j["audio_outputs"].is_array()) << out;
  ASSERT_TRUE(j["hid"].is_array()) << out;
  for (const auto& h : j["hid"]) {
    // "vvvv:pppp product": vendor and product ids as four hex digits each.
    const std::string s = h;
    ASSERT_GE(s.size(), 9u) << s;
    EXPECT_EQ(s[4], ':') << s;
    EXPECT_EQ(s.find_first_not_of("0123456789abcdef", 0), 4u) << s;
  }
  ASSERT_EQ(test::RunCommand("{ " + Cli() + " device list 2>/dev/null; }", &out), 0) << out;
  EXPECT_NE(out.find("Novint Falcons: " + std::to_string(j["falcons"].get<int>()) + "\n"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find(j["audio_outputs"].empty() ? "audio outputs: none\n" : "audio outputs:\n"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find(j["hid"].empty() ? "HID devices: none\n" : "HID devices:\n"),
            std::string::npos)
      << out;
  for (const auto& a : j["audio_outputs"])
    EXPECT_NE(out.find("  " + a.get<std::string>() + "\n"), std::string::npos) << a;
}

// falcon-load: a firmware file that is missing or empty is bad input naming the file and the
// option (never the library's field name); with no Falcon on the bus the work fails (exit 1).
TEST(DeviceCli, FalconLoadNamesTheFirmwareFileAndTheOption) {
  test::TempDir dir;
  std::string out;
  EXPECT_EQ(
      test::RunCommand(Cli() + " device falcon-load --firmware " + dir.File("none.bin"), &out), 2);
  EXPECT_NE(out.find(dir.File("none.bin") + ": --firmware: cannot open the firmware file"),
            std::string::npos)
      << out;
  test::WriteFile(dir.File("empty.bin"), "");
  EXPECT_EQ(
      test::RunCommand(Cli() + " device falcon-load --firmware " + dir.File("empty.bin"), &out), 2);
  EXPECT_NE(out.find(dir.File("empty.bin") + ": --firmware: empty firmware file"),
            std::string::npos)
      << out;
  // Only where no Falcon is connected (never send a made-up firmware to a real one).
  ASSERT_EQ(test::RunCommand("{ " + Cli() + " device list --json 2>/dev/null; }", &out), 0) << out;
  if (nlohmann::json::parse(out)["falcons"].get<int>() == 0) {
    test::WriteFile(dir.File("fw.bin"), std::string(64, '\x5a'));
    EXPECT_EQ(
        test::RunCommand(Cli() + " device falcon-load --firmware " + dir.File("fw.bin"), &out), 1);
    EXPECT_NE(out.find("failed: falcon"), std::string::npos) << out;
  }
}

}  // namespace
}  // namespace hapticlab::cmd_device_test
