// The device factory (devices/src/factory.cpp): requests that cannot name a usable device are
// InputErrors on "<command line>" naming the request's field, before any hardware is touched.

#include "hapticlab/devices/factory.hpp"

#include <gtest/gtest.h>

#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/devices/vendor.hpp"

namespace hapticlab::devices {
namespace {

// The one diagnostic of an InputError thrown by `f`.
template <typename F>
Diagnostic ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    EXPECT_EQ(e.diagnostics().size(), 1u);
    if (!e.diagnostics().empty()) return e.diagnostics()[0];
  }
  ADD_FAILURE() << "no InputError";
  return {};
}

TEST(DeviceFactory, KnowsTheRealBackEnds) {
  EXPECT_TRUE(IsRealDevice("falcon"));
  EXPECT_TRUE(IsRealDevice("dhd"));
  EXPECT_TRUE(IsRealDevice("openhaptics"));
  EXPECT_FALSE(IsRealDevice("sim"));
  EXPECT_FALSE(IsRealDevice("falcon-twin"));
}

TEST(DeviceFactory, RefusesASimulatedOrUnknownName) {
  for (const char* name : {"sim", "falcon-twin", "phantom"}) {
    const auto d = ErrorOf([&] { (void)OpenRealDevice({.device = name}); });
    EXPECT_EQ(d.file, "<command line>") << name;
    EXPECT_EQ(d.field, "device") << name;
    EXPECT_NE(d.message.find(name), std::string::npos) << d.message;
  }
}

TEST(DeviceFactory, AFalconWithoutFirmwareNamesTheFirmwareField) {
  const auto d = ErrorOf([] { (void)OpenRealDevice({.device = "falcon"}); });
  EXPECT_EQ(d.field, "firmware");
  EXPECT_NE(d.message.find("firmware"), std::string::npos) << d.message;
}

TEST(DeviceFactory, AVendorBackEndThisBuildLacksIsNamed) {
  if (HaveDhd()) GTEST_SKIP() << "this build has the Force Dimension SDK";
  const auto d = ErrorOf([] { (void)OpenRealDevice({.device = "dhd"}); });
  EXPECT_EQ(d.field, "device");
  EXPECT_NE(d.message.find("SDK"), std::string::npos) << d.message;
}

TEST(DeviceFactory, ARatingBoxIdIsHexVidColonPid) {
  for (const char* bad : {"046d", "046d:", "xyz:c216", "046d:c216x", "1046d:c216"}) {
    const auto d = ErrorOf([&] { (void)OpenRatingBox(bad, "layout.toml"); });
    EXPECT_EQ(d.field, "rating_box") << bad;
  }
  const auto d = ErrorOf([] { (void)OpenRatingBox("046d:c216", ""); });
  EXPECT_EQ(d.field, "rating_layout");
}

}  // namespace
}  // namespace hapticlab::devices
