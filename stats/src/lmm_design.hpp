#pragma once
// Internal to the stats module: the design matrices of a linear mixed model (lmm.cpp).

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <string>
#include <vector>

#include "hapticlab/stats/lmm.hpp"

namespace hapticlab::stats::detail {

struct LmmDesign {
  Eigen::VectorXd y;
  Eigen::MatrixXd X;                       ///< n x p, intercept first, R's column order
  std::vector<std::string> x_names;
  struct Term {
    std::string name;
    std::vector<int> columns;              ///< of X
  };
  std::vector<Term> x_terms;               ///< fixed terms (no intercept), for the F tests
  Eigen::SparseMatrix<double> Z;           ///< n x q; block k: level-major, p_k columns per level
  struct Block {
    std::string group;
    int levels = 0, p = 0, offset = 0;     ///< offset: first column in Z
    std::vector<std::string> names;
  };
  std::vector<Block> blocks;               ///< lme4's order: most levels first
};

/// @throws hapticlab::InputError (data.source, column) for a missing column, a factor with one
///         level, or an unsupported random term
LmmDesign BuildLmmDesign(const LongTable& data, const LmmFormula& f);

}  // namespace hapticlab::stats::detail
