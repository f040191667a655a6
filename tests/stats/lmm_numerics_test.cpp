// The LMM fit's numerical tools (lmm_numerics.cpp) against closed forms: bounded Nelder-Mead
// on Rosenbrock's function (minimum (1, 1); Rosenbrock 1960) and on a quadratic whose
// minimum lies outside the bound, and the Richardson-extrapolated Hessian and Jacobian against
// analytic derivatives.

#include "../../stats/src/lmm_numerics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace hapticlab::stats::lmm_internal::lmm_numerics_test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(LmmNumerics, NelderMeadFindsRosenbrocksMinimum) {
  const auto rosenbrock = [](const Eigen::VectorXd& x) {
    return 100 * std::pow(x[1] - x[0] * x[0], 2) + std::pow(1 - x[0], 2);
  };
  Eigen::VectorXd x0(2);
  x0 << -1.2, 1.0;  // the classical start
  const auto m = NelderMead(rosenbrock, x0, {-kInf, -kInf}, 20000);
  EXPECT_TRUE(m.converged);
  EXPECT_NEAR(m.x[0], 1.0, 1e-4);
  EXPECT_NEAR(m.x[1], 1.0, 1e-4);
  EXPECT_LT(m.f, 1e-8);
  EXPECT_LE(m.evaluations, 20000);
}

TEST(LmmNumerics, NelderMeadStopsOnTheBound) {
  // (x + 1)^2 + (y - 2)^2 with x >= 0: the constrained minimum is (0, 2), f = 1.
  const auto f = [](const Eigen::VectorXd& x) {
    return std::pow(x[0] + 1, 2) + std::pow(x[1] - 2, 2);
  };
  Eigen::VectorXd x0(2);
  x0 << 1.0, 0.0;
  const auto m = NelderMead(f, x0, {0.0, -kInf}, 5000);
  EXPECT_GE(m.x[0], 0.0);
  EXPECT_NEAR(m.x[0], 0.0, 1e-5);
  EXPECT_NEAR(m.x[1], 2.0, 1e-5);
  EXPECT_NEAR(m.f, 1.0, 1e-8);
}

TEST(LmmNumerics, HessianAndJacobianMatchAnalyticDerivatives) {
  // f = x^3 y + e^x y^2: f_xx = 6xy + e^x y^2, f_xy = 3x^2 + 2 e^x y, f_yy = 2 e^x.
  const auto f = [](const Eigen::VectorXd& v) {
    return std::pow(v[0], 3) * v[1] + std::exp(v[0]) * v[1] * v[1];
  };
  Eigen::VectorXd x(2);
  x << 0.5, -1.2;
  const double e = std::exp(x[0]);
  Eigen::Matrix2d want;
  want << 6 * x[0] * x[1] + e * x[1] * x[1], 3 * x[0] * x[0] + 2 * e * x[1],
      3 * x[0] * x[0] + 2 * e * x[1], 2 * e;
  const Eigen::MatrixXd h = Hessian(f, x);
  ASSERT_EQ(h.rows(), 2);
  ASSERT_EQ(h.cols(), 2);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) EXPECT_NEAR(h(i, j), want(i, j), 1e-6 * (1 + std::abs(want(i, j))));

  // C(x) = [[x0^2, sin x1], [x0 x1, e^x0]]: dC/dx0 = [[2 x0, 0], [x1, e^x0]],
  // dC/dx1 = [[0, cos x1], [x0, 0]].
  const auto c = [](const Eigen::VectorXd& v) {
    Eigen::MatrixXd m(2, 2);
    m << v[0] * v[0], std::sin(v[1]), v[0] * v[1], std::exp(v[0]);
    return m;
  };
  const auto j = Jacobian(c, x);
  ASSERT_EQ(j.size(), 2u);
  Eigen::Matrix2d d0, d1;
  d0 << 2 * x[0], 0, x[1], e;
  d1 << 0, std::cos(x[1]), x[0], 0;
  EXPECT_LT((j[0] - d0).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((j[1] - d1).cwiseAbs().maxCoeff(), 1e-8);
}

}  // namespace
}  // namespace hapticlab::stats::lmm_internal::lmm_numerics_test
