#pragma once
// Internal to the stats module: the contrast and sphericity tools of the ANOVA (anova.cpp),
// shared with the repeated-measures ANOVA (anova_rm.cpp). Not installed.

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "hapticlab/stats/anova.hpp"

namespace hapticlab::stats::anova_internal {

using Eigen::MatrixXd;

/// Orthonormal Helmert contrasts for k levels: k x (k-1), columns orthogonal to 1.
MatrixXd Helmert(int k);
MatrixXd Kron(const MatrixXd& a, const MatrixXd& b);
/// Mauchly's test and the GG/HF epsilons of a covariance S of orthonormal contrasts.
/// `nu`: the error df of the multivariate model; `columns`: the cells of the design.
Sphericity FromCov(const MatrixXd& S, double nu, int columns);
/// Sum-to-zero contrasts (R's contr.sum): k x (k-1).
MatrixXd ContrSum(int k);
/// Non-empty subsets of n factors as bit masks in afex's and car's term order.
std::vector<int> Terms(int n);
/// "a:b" of the factors in `mask`.
std::string TermName(int mask, const std::vector<std::string>& names);

}  // namespace hapticlab::stats::anova_internal
