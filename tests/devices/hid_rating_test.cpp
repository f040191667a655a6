// The rating box's HID reports against recorded fixtures, and layout files.

#include "hapticlab/devices/hid_rating.hpp"

#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::devices::hid_rating_test {
namespace {

TEST(HidRating, ParsesReportsOfASliderBox) {
  // A 10-bit slider box: report id 1, position little-endian at bytes 1-2, confirm on bit 0 of
  // byte 3 (reports as the box sends them, id first).
  HidReportLayout L;
  L.report_id = 1;
  L.position_offset = 0;
  L.position_bytes = 2;
  L.raw_min = 0;
  L.raw_max = 1023;
  L.button_offset = 2;
  L.button_bit = 0;
  const std::uint8_t mid[] = {0x01, 0x00, 0x02, 0x00};    // 512, not pressed
  const std::uint8_t top[] = {0x01, 0xff, 0x03, 0x01};    // 1023, confirm
  const std::uint8_t other[] = {0x02, 0xff, 0x03, 0x01};  // another report id
  const std::uint8_t shorty[] = {0x01, 0x00};             // truncated
  const std::uint8_t wild[] = {0x01, 0xff, 0x7f, 0x00};   // 32767: wrong layout or a glitch
  auto e = ParseHidReport(L, mid, sizeof mid);
  ASSERT_TRUE(e.valid);
  EXPECT_NEAR(e.position, 512.0 / 1023, 1e-12);
  EXPECT_FALSE(e.confirm);
  e = ParseHidReport(L, top, sizeof top);
  ASSERT_TRUE(e.valid);
  EXPECT_DOUBLE_EQ(e.position, 1.0);
  EXPECT_TRUE(e.confirm);
  EXPECT_FALSE(ParseHidReport(L, other, sizeof other).valid);
  EXPECT_FALSE(ParseHidReport(L, shorty, sizeof shorty).valid);
  EXPECT_FALSE(ParseHidReport(L, wild, sizeof wild).valid);
}

TEST(HidRating, ParsesAReversedSignedKnob) {
  // A knob reporting a signed byte -100..100, no report ids, reversed (raw_min > raw_max).
  HidReportLayout L;
  L.report_id = -1;
  L.position_offset = 1;
  L.position_bytes = 1;
  L.is_signed = true;
  L.raw_min = 100;
  L.raw_max = -100;
  L.button_offset = 0;
  L.button_bit = 7;
  const std::uint8_t r[] = {0x80, static_cast<std::uint8_t>(-50)};
  const auto e = ParseHidReport(L, r, sizeof r);
  ASSERT_TRUE(e.valid);
  EXPECT_NEAR(e.position, 0.75, 1e-12);
  EXPECT_TRUE(e.confirm);
}

TEST(HidRating, LayoutFilesAreCheckedWithFileLineAndKey) {
  test::TempDir dir;
  test::WriteFile(dir.File("box.toml"),
                  "report_id = 1\nposition_bytes = 2\nraw_max = 4095\nbutton_bit = 2\n");
  const auto L = LoadHidLayout(dir.File("box.toml"));
  EXPECT_EQ(L.report_id, 1);
  EXPECT_EQ(L.raw_max, 4095);
  EXPECT_EQ(L.button_bit, 2);
  test::WriteFile(dir.File("bad.toml"), "report_id = 1\nposition_bytes = 3\nbuton_bit = 2\n");
  try {
    LoadHidLayout(dir.File("bad.toml"));
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("bad.toml:3: buton_bit: unknown key"), std::string::npos) << m;
    EXPECT_NE(m.find("position_bytes"), std::string::npos) << m;
  }
}

TEST(HidRating, OffsetsOutsideAReportAreRefusedBeforeTheyIndexIt) {
  // -1 or 1e10 used to be cast to int unchecked and then index a 64-byte report.
  test::TempDir dir;
  for (const char* bad : {"position_offset = -1\n", "position_offset = 1e10\n",
                          "button_offset = 64\n", "report_id = 4294967296\n"}) {
    SCOPED_TRACE(bad);
    test::WriteFile(dir.File("o.toml"), bad);
    try {
      LoadHidLayout(dir.File("o.toml"));
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("o.toml:1:"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace hapticlab::devices::hid_rating_test
