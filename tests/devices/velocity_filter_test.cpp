// The velocity a position-only device reports, against the first-order low-pass it claims:
// for a ramp p = u t read every dt, v_k = u (1 - (1 - a)^(k-1)) with a = 1 - exp(-2 pi f_c dt)
// (the first reading has no difference yet).

#include "hapticlab/devices/velocity_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace hapticlab::devices::velocity_filter_test {
namespace {

TEST(VelocityFilter, ARampConvergesLikeAFirstOrderLowPass) {
  const Eigen::Vector3d u(0.05, -0.02, 0.01);  // m/s
  const double dt = 1e-3, fc = 100;
  const double a = 1 - std::exp(-2 * std::numbers::pi * fc * dt);
  VelocityFilter f;
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector3d v = f.Update(u * (k * dt), k * dt, fc);
    const Eigen::Vector3d expected = u * (1 - std::pow(1 - a, k));
    ASSERT_LT((v - expected).norm(), 1e-9 * u.norm()) << "reading " << k;
  }
}

TEST(VelocityFilter, IrregularStepsUseTheirOwnDtAndStaleReadingsAreIgnored) {
  const double fc = 50;
  VelocityFilter f;
  f.Update(Eigen::Vector3d::Zero(), 0.0, fc);
  // One step of 4 ms at 0.1 m/s: the velocity moves a(4 ms) of the way.
  const Eigen::Vector3d v1 = f.Update(Eigen::Vector3d(0.1 * 0.004, 0, 0), 0.004, fc);
  EXPECT_NEAR(v1.x(), 0.1 * (1 - std::exp(-2 * std::numbers::pi * fc * 0.004)), 1e-12);
  // A reading at the same time changes no velocity (no division by zero) ...
  const Eigen::Vector3d v2 = f.Update(Eigen::Vector3d(1, 1, 1), 0.004, fc);
  EXPECT_EQ(v2, v1);
  // ... and Reset forgets the last position: the next reading is a first reading again.
  f.Reset();
  EXPECT_EQ(f.v_mps(), Eigen::Vector3d::Zero());
  EXPECT_EQ(f.Update(Eigen::Vector3d(5, 5, 5), 1.0, fc), Eigen::Vector3d::Zero());
}

}  // namespace
}  // namespace hapticlab::devices::velocity_filter_test
