#include "hapticlab/renderer/height_map.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::renderer::height_map_test {
namespace {

TEST(HeightMap, BilinearIsExactOnAPlane) {
  // h = 1e-5 + 2e-3 x + 5e-4 y sampled on a 4 x 3 grid with 1 mm pitch.
  const double pitch = 1e-3;
  std::vector<float> h;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j)
      h.push_back(static_cast<float>(1e-5 + 2e-3 * j * pitch + 5e-4 * i * pitch));
  HeightMap m(4, 3, pitch, h);
  const auto s = m.Sample(1.3e-3, 0.6e-3);
  EXPECT_NEAR(s.h_m, 1e-5 + 2e-3 * 1.3e-3 + 5e-4 * 0.6e-3, 1e-10);
  EXPECT_NEAR(s.dhdx, 2e-3, 1e-6);
  EXPECT_NEAR(s.dhdy, 5e-4, 1e-6);
  EXPECT_DOUBLE_EQ(m.min_m(), h.front());
  EXPECT_DOUBLE_EQ(m.Normalized(m.max_m()), 1.0);
}

TEST(HeightMap, TilesOutsideTheSampledArea) {
  HeightMap m = HeightMap::Sine(1e-5, 2e-3, 1e-5, 256);
  const auto a = m.Sample(0.3e-3, 0);
  const auto b = m.Sample(0.3e-3 + 5 * 2e-3, 7.0);
  const auto c = m.Sample(0.3e-3 - 3 * 2e-3, -1.0);
  EXPECT_NEAR(a.h_m, b.h_m, 1e-12);
  EXPECT_NEAR(a.h_m, c.h_m, 1e-12);
}

TEST(HeightMap, RawFileRoundTripAndErrors) {
  test::TempDir dir;
  HeightMap m(3, 2, 2e-5, {0.f, 1e-6f, 2e-6f, 3e-6f, 4e-6f, 5e-6f});
  m.SaveRawF32(dir.File("h.f32"));
  const auto back = HeightMap::LoadRawF32(dir.File("h.f32"), 3, 2, 2e-5);
  EXPECT_EQ(back.data(), m.data());
  try {
    HeightMap::LoadRawF32(dir.File("h.f32"), 4, 2, 2e-5);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("h.f32"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("24 bytes"), std::string::npos) << e.what();
  }
  const float nan = std::nanf("");
  test::WriteFile(dir.File("bad.f32"), std::string(reinterpret_cast<const char*>(&nan), 4));
  EXPECT_THROW(HeightMap::LoadRawF32(dir.File("bad.f32"), 1, 1, 1e-5), InputError);
  EXPECT_THROW(HeightMap::LoadRawF32(dir.File("none.f32"), 1, 1, 1e-5), InputError);
}

}  // namespace
}  // namespace hapticlab::renderer::height_map_test
