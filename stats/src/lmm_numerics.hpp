#pragma once
// Numerical tools of the LMM fit (stats/src/lmm.cpp): bounded Nelder-Mead and
// Richardson-extrapolated finite differences (numDeriv's method). Not installed.

#include <Eigen/Core>
#include <functional>
#include <vector>

namespace hapticlab::stats::lmm_internal {

// Nelder-Mead with bounds by projection, restarted from its best point until a restart no
// longer improves. Hand-written: no bound-constrained derivative-free optimizer is in the
// tree (lme4 uses BOBYQA from NLopt, which is not installed; Ceres has no bounds for general
// objectives). The deviance is smooth and θ has few elements, so this reaches lme4's optimum
// (checked against lme4 with tight BOBYQA tolerances in tests/stats/lmm_test.cpp).
struct Minimum {
  Eigen::VectorXd x;
  double f = 0;
  int evaluations = 0;
  bool converged = false;
};

/// Minimises f from x0 with x >= lower (element-wise), at most max_evals evaluations.
Minimum NelderMead(const std::function<double(const Eigen::VectorXd&)>& f,
                   const Eigen::VectorXd& x0, const std::vector<double>& lower, int max_evals);
/// Hessian of f at x by Richardson-extrapolated central differences.
Eigen::MatrixXd Hessian(const std::function<double(const Eigen::VectorXd&)>& f,
                        const Eigen::VectorXd& x);
/// d C / d x_i for a matrix-valued C(x), each by Richardson-extrapolated central differences.
std::vector<Eigen::MatrixXd> Jacobian(
    const std::function<Eigen::MatrixXd(const Eigen::VectorXd&)>& C, const Eigen::VectorXd& x);

}  // namespace hapticlab::stats::lmm_internal
