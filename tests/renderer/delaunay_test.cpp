#include "hapticlab/renderer/delaunay.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "hapticlab/core/status.hpp"
#include "hapticlab/renderer/material.hpp"

namespace hapticlab::renderer::delaunay_test {
namespace {

double Area(const std::vector<double>& x, const std::vector<double>& y,
            const std::array<int, 3>& t) {
  const auto a = static_cast<std::size_t>(t[0]), b = static_cast<std::size_t>(t[1]),
             c = static_cast<std::size_t>(t[2]);
  return 0.5 * std::abs((x[b] - x[a]) * (y[c] - y[a]) - (x[c] - x[a]) * (y[b] - y[a]));
}

TEST(Delaunay, TrianglesTileTheConvexHullWithEmptyCircumcircles) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<double> x, y;
  // Corners fix the hull to the unit square (area 1), then random interior points.
  for (auto [a, b] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {1.0, 1.0}}) {
    x.push_back(a);
    y.push_back(b);
  }
  for (int i = 0; i < 40; ++i) {
    x.push_back(u(rng));
    y.push_back(u(rng));
  }
  const auto tris = DelaunayTriangulate(x, y);
  double area = 0;
  for (const auto& t : tris) area += Area(x, y, t);
  EXPECT_NEAR(area, 1.0, 1e-9);
  EXPECT_EQ(tris.size(), 2u * x.size() - 4u - 2u);  // 2n - h - 2 with h = 4 hull points
  // Empty circumcircle property.
  for (const auto& t : tris) {
    const double ax = x[static_cast<std::size_t>(t[0])], ay = y[static_cast<std::size_t>(t[0])];
    const double bx = x[static_cast<std::size_t>(t[1])], by = y[static_cast<std::size_t>(t[1])];
    const double cx = x[static_cast<std::size_t>(t[2])], cy = y[static_cast<std::size_t>(t[2])];
    const double d = 2 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by));
    const double ux = ((ax * ax + ay * ay) * (by - cy) + (bx * bx + by * by) * (cy - ay) +
                       (cx * cx + cy * cy) * (ay - by)) /
                      d;
    const double uy = ((ax * ax + ay * ay) * (cx - bx) + (bx * bx + by * by) * (ax - cx) +
                       (cx * cx + cy * cy) * (bx - ax)) /
                      d;
    const double r2 = (ax - ux) * (ax - ux) + (ay - uy) * (ay - uy);
    for (std::size_t i = 0; i < x.size(); ++i)
      EXPECT_GE((x[i] - ux) * (x[i] - ux) + (y[i] - uy) * (y[i] - uy), r2 * (1 - 1e-9));
  }
}

TEST(Delaunay, CollinearOrTooFewPointsAreErrors) {
  EXPECT_THROW(DelaunayTriangulate({0, 1}, {0, 1}), PreconditionError);
  EXPECT_THROW(DelaunayTriangulate({0, 1, 2}, {0, 0, 0}), PreconditionError);
}

TEST(Delaunay, ScatteredCellsInAModelFileAreTriangulatedOnLoad) {
  const auto m = ParseMaterial(R"(name = "s"
[contact]
texture_K = 100.0
[friction]
kappa_N_per_m = 100.0
mu_k = 0.2
[vibration]
sample_rate_hz = 2000
[[vibration.cells]]
speed_mps = 0.02
force_N = 0.5
ar = [0.5]
variance = 1.0
[[vibration.cells]]
speed_mps = 0.10
force_N = 0.6
ar = [0.4]
variance = 1.0
[[vibration.cells]]
speed_mps = 0.05
force_N = 1.8
ar = [0.3]
variance = 1.0
[[vibration.cells]]
speed_mps = 0.12
force_N = 1.5
ar = [0.2]
variance = 1.0
)",
                               "s.toml");
  EXPECT_EQ(m.vibration.triangles.size(), 2u);
}

}  // namespace
}  // namespace hapticlab::renderer::delaunay_test
