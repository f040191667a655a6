// What the device back-ends share (devices/src/factory.cpp): the one device error message, and
// rating-box requests that cannot name a usable box are InputErrors on "<command line>" naming
// the request's field, before any hardware is touched. Opening back-ends by name:
// tests/runner/open_rig_test.cpp.

#include "hapticlab/devices/factory.hpp"

#include <gtest/gtest.h>

#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/error_of.hpp"

namespace hapticlab::devices::factory_test {
namespace {

using test::ErrorOf;

TEST(DeviceFactory, TheDeviceErrorSaysWhatToCheck) {
  const std::string fw = DeviceErrorMessage("falcon", "no device", true);
  EXPECT_EQ(fw.rfind("falcon: no device; check ", 0), 0u) << fw;
  EXPECT_NE(fw.find("firmware file"), std::string::npos) << fw;
  const std::string vendor = DeviceErrorMessage("dhd", "dhd: gone", false);
  EXPECT_EQ(vendor.rfind("dhd: gone; check ", 0), 0u) << vendor;  // not named twice
  EXPECT_NE(vendor.find("vendor's driver"), std::string::npos) << vendor;
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
}  // namespace hapticlab::devices::factory_test
