#include "hapticlab/renderer/vibration.hpp"

#include <gtest/gtest.h>

#include <random>

#include "hapticlab/test/test_util.hpp"
#include "test_materials.hpp"

namespace hapticlab::renderer::vibration_test {
namespace {

void ExpectFilterIsCell(const ArFilter& f, const ArCell& c) {
  ASSERT_EQ(f.order, static_cast<int>(c.coeffs.size()));
  for (std::size_t i = 0; i < c.coeffs.size(); ++i) EXPECT_NEAR(f.c[i], c.coeffs[i], 1e-10);
  EXPECT_NEAR(f.sigma * f.sigma, c.variance, 1e-12);
}

TEST(Vibration, GridInterpolationAtAModelsOwnPointReproducesIt) {
  VibrationInterpolator interp(test::GridBank());
  for (const auto& c : interp.bank().cells) {
    ArFilter f;
    interp.Interpolate(c.speed_mps, c.force_N, true, &f);
    EXPECT_TRUE(f.active);
    ExpectFilterIsCell(f, c);
  }
}

TEST(Vibration, GridWeightsAreBilinearAndClampedAtTheEdges) {
  VibrationInterpolator interp(test::GridBank());
  const auto w = interp.Weights(0.06, 0.54 + 0.25 * (1.18 - 0.54));
  double sum = 0, s_mean = 0, f_mean = 0;
  for (int k = 0; k < w.count; ++k) {
    const auto& c =
        interp.bank().cells[static_cast<std::size_t>(w.cell[static_cast<std::size_t>(k)])];
    sum += w.weight[static_cast<std::size_t>(k)];
    s_mean += w.weight[static_cast<std::size_t>(k)] * c.speed_mps;
    f_mean += w.weight[static_cast<std::size_t>(k)] * c.force_N;
  }
  EXPECT_NEAR(sum, 1, 1e-12);
  EXPECT_NEAR(s_mean, 0.06, 1e-12);  // bilinear weights reproduce the point
  EXPECT_NEAR(f_mean, 0.54 + 0.25 * (1.18 - 0.54), 1e-12);
  // Far outside: the corner model.
  ArFilter f;
  interp.Interpolate(5.0, 100.0, true, &f);
  ExpectFilterIsCell(f, interp.bank().cells.back());
}

TEST(Vibration, TriangulationReproducesVerticesAndInterpolatesInside) {
  VibrationBank b = test::GridBank();
  // Same cells as scattered points with a hand triangulation of the 3 x 3 grid.
  b.grid_speeds_mps.clear();
  b.grid_forces_N.clear();
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      const int a = i * 3 + j;
      b.triangles.push_back({a, a + 1, a + 4});
      b.triangles.push_back({a, a + 3, a + 4});
    }
  VibrationInterpolator interp(b);
  for (const auto& c : b.cells) {
    ArFilter f;
    interp.Interpolate(c.speed_mps, c.force_N, true, &f);
    ExpectFilterIsCell(f, c);
  }
  const auto w = interp.Weights(0.05, 0.7);
  EXPECT_EQ(w.count, 3);
  double s = 0, fo = 0;
  for (int k = 0; k < 3; ++k) {
    s += w.weight[static_cast<std::size_t>(k)] *
         b.cells[static_cast<std::size_t>(w.cell[static_cast<std::size_t>(k)])].speed_mps;
    fo += w.weight[static_cast<std::size_t>(k)] *
          b.cells[static_cast<std::size_t>(w.cell[static_cast<std::size_t>(k)])].force_N;
  }
  EXPECT_NEAR(s, 0.05, 1e-12);
  EXPECT_NEAR(fo, 0.7, 1e-12);
}

TEST(Vibration, EveryInterpolatedFilterIsStable) {
  VibrationInterpolator interp(test::GridBank(20));
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> sp(0.0, 0.2), fo(0.0, 3.0);
  for (int t = 0; t < 2000; ++t) {
    ArFilter f;
    interp.Interpolate(0.011 + sp(rng), fo(rng), true, &f);
    ASSERT_TRUE(IsStableAr(std::span<const double>(f.c.data(), static_cast<std::size_t>(f.order))));
  }
}

TEST(Vibration, OffBelowOneCentimetrePerSecondAndOutOfContact) {
  VibrationInterpolator interp(test::GridBank());
  ArFilter f;
  interp.Interpolate(0.009, 1.0, true, &f);
  EXPECT_FALSE(f.active);
  interp.Interpolate(0.05, 1.0, false, &f);
  EXPECT_FALSE(f.active);
  ArSynth s;
  EXPECT_EQ(s.Step(f), 0.0);
}

TEST(Vibration, InterpolationAndSynthesisAllocateNothing) {
  VibrationInterpolator interp(test::GridBank(20));
  ArSynth s;
  ArFilter f;
  test::NoAllocGuard guard;
  for (int k = 0; k < 1000; ++k) {
    interp.Interpolate(0.05 + 1e-5 * k, 1.0, true, &f);
    s.Step(f);
  }
  EXPECT_EQ(guard.count(), 0u);
}

TEST(Vibration, NoiseIsDeterministicPerSeed) {
  GaussianNoise a(5), b(5), c(6);
  for (int k = 0; k < 100; ++k) {
    const double x = a.Normal();
    EXPECT_EQ(x, b.Normal());
    EXPECT_NE(x, c.Normal());
  }
}

}  // namespace
}  // namespace hapticlab::renderer::vibration_test
