// Readers range-check numbers before every narrowing conversion: hostile values are an
// InputError naming file, line and field, never undefined behaviour (UBSan runs these in CI).

#include <gtest/gtest.h>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/penn_import.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::renderer::input_guard_test {
namespace {

// The InputError message of `f` ("" when it succeeds).
template <class F>
std::string Refusal(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(InputGuard, HeightMapSidesOutOfIntRangeAreRefused) {
  test::TempDir dir;
  test::WriteFile(dir.File("h.raw"), std::string(16, '\0'));
  const std::string base =
      "name = \"x\"\n[contact]\ntexture_K = 100.0\n[friction]\nkappa_N_per_m = 100.0\nmu_k = 0.2\n"
      "[geometry]\nkind = \"file\"\nfile = \"h.raw\"\npitch_m = 0.001\n";
  for (const char* sides : {"width = 1e10\nheight = 1\n", "width = 2\nheight = -4294967296\n",
                            "width = 2.5\nheight = 2\n"}) {
    SCOPED_TRACE(sides);
    const std::string msg = Refusal([&] { ParseMaterial(base + sides, dir.File("m.toml")); });
    EXPECT_NE(msg.find("m.toml:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("whole number of samples"), std::string::npos) << msg;
  }
  EXPECT_EQ(Refusal([&] { ParseMaterial(base + "width = 2\nheight = 2\n", dir.File("m.toml")); }),
            "");
}

TEST(InputGuard, PennIndicesOutOfIntRangeAreRefusedWithTheirLine) {
  test::TempDir dir;
  const std::string xml =
      "<?xml "
      "version=\"1.0\"?>\n<modelSet>\n<material>T</material>\n<SampleRate>10000</"
      "SampleRate>\n<mu>0.4</mu>\n"
      "<numMod>1e300</numMod>\n<numARCoeff>4294967296</numARCoeff>\n"
      "<speedList><value>0</value></speedList>\n<forceList><value>0.5</value></forceList>\n"
      "<tri><value>4294967295</value><value>-3e12</value><value>1</value></tri>\n"
      "<model><modNum>9e18</modNum><ARcoeff><value>1</value></ARcoeff><ARlsf></ARlsf><var>0.1</"
      "var></model>\n"
      "</modelSet>\n";
  test::WriteFile(dir.File("p.xml"), xml);
  const std::string msg = Refusal([&] { ImportPennXml(dir.File("p.xml")); });
  EXPECT_NE(msg.find("p.xml:10: tri"), std::string::npos) << msg;
  EXPECT_NE(msg.find("modNum"), std::string::npos) << msg;
  // Malformed XML is reported with its line, not a byte offset.
  test::WriteFile(dir.File("bad.xml"),
                  "<?xml version=\"1.0\"?>\n<modelSet>\n<mu>1</mu>\n<tri>\n</modelSet>\n");
  const std::string bad = Refusal([&] { ImportPennXml(dir.File("bad.xml")); });
  EXPECT_NE(bad.find("bad.xml:5:"), std::string::npos) << bad;
}

}  // namespace
}  // namespace hapticlab::renderer::input_guard_test
