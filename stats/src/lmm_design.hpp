#pragma once
// Internal to the stats module: the design matrices of a linear mixed model (lmm.cpp).

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <functional>
#include <string>
#include <vector>

#include "hapticlab/stats/lmm.hpp"

namespace hapticlab::stats::detail {

struct LmmDesign {
  Eigen::VectorXd y;
  Eigen::MatrixXd X;  ///< n x p, intercept first, R's column order
  std::vector<std::string> x_names;
  struct Term {
    std::string name;
    std::vector<int> columns;  ///< of X
  };
  std::vector<Term> x_terms;      ///< fixed terms (no intercept), for the F tests
  Eigen::SparseMatrix<double> Z;  ///< n x q; block k: level-major, p_k columns per level
  struct Block {
    std::string group;
    int levels = 0, p = 0, offset = 0;  ///< offset: first column in Z
    std::vector<std::string> names;
  };
  std::vector<Block> blocks;  ///< lme4's order: most levels first
};

/// The values of a numeric column by name (n values; "" asks for any column of length n).
using ColumnLookup = std::function<Eigen::VectorXd(const std::string&)>;
/// A formula variable that is a plain column name (not a function of columns).
bool IsColumnName(const std::string& label);
/// The columns a formula variable ("x", "log(x + 1)", "I(a*b)") reads.
std::vector<std::string> ExprColumns(const std::string& label);
/// "poly(x, 2)": the expression inside and the degree.
bool PolyLabel(const std::string& label, std::string& inner, int& degree);
/// The values of a formula variable (not poly).
Eigen::VectorXd EvalExpr(const std::string& label, const ColumnLookup& column);

/// @throws hapticlab::InputError (data.source, column) for a missing column, a factor with one
///         level, or an unsupported random term
LmmDesign BuildLmmDesign(const LongTable& data, const LmmFormula& f);

/// pbkrtest's vcovAdj: the Kenward-Roger adjusted cov(β̂) and what the df need.
struct KrAdjusted {
  Eigen::MatrixXd PhiA;            ///< adjusted covariance of β̂
  std::vector<Eigen::MatrixXd> P;  ///< -X'V⁻¹ G_r V⁻¹ X
  Eigen::MatrixXd W;               ///< 2 × inverse expected information of γ
};
/// @param gamma the variance-covariance elements (per block its covariance's lower
///        triangle, column-major; then σ²) @param Phi unadjusted cov(β̂) = (X'V⁻¹X)⁻¹
KrAdjusted KenwardRogerVcov(const LmmDesign& d, const std::vector<double>& gamma,
                            const Eigen::MatrixXd& Phi);

struct KrTest {
  double ddf = 0, F = 0, scaling = 1;  ///< F already scaled (pbkrtest's Fstat)
};
/// pbkrtest's .KR_adjust for H0: L β = 0 (L of full row rank).
KrTest KenwardRogerTest(const KrAdjusted& a, const Eigen::MatrixXd& Phi, const Eigen::MatrixXd& L,
                        const Eigen::VectorXd& beta);

}  // namespace hapticlab::stats::detail
