#pragma once
/// @file Linear mixed models fitted as lme4::lmer does (Bates, Mächler, Bolker & Walker 2015,
/// "Fitting linear mixed-effects models using lme4", J. Stat. Softw. 67(1), section 3):
/// y = X β + Z b + ε, b = Λ(θ) u, u ~ N(0, σ² I), ε ~ N(0, σ² I). For a given θ the penalised
/// least squares system is solved with a sparse Cholesky factor (Eigen's SimplicialLLT) of
/// Λ'Z'ZΛ + I, β and σ² are profiled out, and the profiled REML or ML deviance is minimised
/// over θ (diagonal elements of each relative covariance factor ≥ 0).
///
/// Inference follows lmerTest 3.1: the deviance as a function of (θ, σ) gives the asymptotic
/// covariance of the variance parameters, A = 2 H⁻¹; the Satterthwaite df of a contrast l is
/// 2 (l'Cl)² / (g'Ag) with g the gradient of l'C(θ, σ)l, C = cov(β̂); multi-df F tests (type 3
/// with sum-to-zero contrasts, as afex::mixed / anova(m, type = 3)) use lmerTest's eigen
/// decomposition of L C L' (Fai & Cornelius 1996). Derivatives are central differences with
/// Richardson extrapolation (lmerTest uses numDeriv's, the same method). Kenward-Roger
/// (options.kenward_roger, REML only) follows pbkrtest 0.5 (lmm_kr.cpp).
///
/// Formula syntax (a subset of lme4's): `y ~ a * b + c + a:c + (1 + a | g) + (1 | h)` with
/// `*` (all interactions), `:`, `+`; `0 +` or `- 1` for no intercept; random terms `(1 | g)`,
/// `(1 + x + ... | g)`, `(x | g)` (intercept implied), `(0 + x | g)`, uncorrelated terms
/// `(x || g)` (lme4's expansion: `(1 | g) + (0 + x | g)`), interaction grouping `(1 | a:b)` and
/// nesting `(1 | a/b)` (= `(1 | b:a) + (1 | a)`); several terms may share or cross grouping
/// factors. The response and numeric predictors may be functions of a numeric column: `log`,
/// `log10`, `log2`, `exp`, `sqrt`, `abs`, `scale` (centred, divided by the SD) and `I()` with
/// + - * / ^ arithmetic; they are named as R names them (`I(Days^2)`, `log(Days + 1)`).
/// A column is numeric when every value parses as a number (as read.csv decides), otherwise a
/// factor (levels sorted). Factors are coded as R codes them with contrasts = contr.sum: in a
/// term, a factor gets sum-to-zero contrasts (`method1`, `method2`) when the term without it is
/// in the model (the intercept counts as the empty term), else one indicator per level
/// (`methodaudio`), so `0 + method` gives one mean per level. Grouping columns are always
/// factors; R names a grouping factor that appears twice `g.1` (VarCorr), and so do we.

#include <string>
#include <utility>
#include <vector>

#include "hapticlab/core/solver_summary.hpp"
#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::stats {

/// A parsed model formula: terms are lists of column names (an interaction has several).
struct LmmFormula {
  std::string response;       ///< the response column
  std::string response_term;  ///< as R prints it: "Reaction" or "log(Reaction)"
  bool intercept = true;      ///< of the fixed part
  /// Without the intercept, in R's order (by degree); a variable is a column or a function of
  /// one as R prints it ("I(Days^2)").
  std::vector<std::vector<std::string>> fixed;
  struct Random {
    bool intercept = true;
    std::vector<std::vector<std::string>> terms;  ///< slope terms (no intercept)
    std::string group;                            ///< "g" or "b:a"
    std::vector<std::string> group_factors;       ///< the columns whose interaction groups
  };
  std::vector<Random> random;
  /// Every column the formula names (response first).
  std::vector<std::string> Columns() const;
};

/// @throws hapticlab::InputError naming `source` and the field "formula" for bad syntax
LmmFormula ParseLmmFormula(const std::string& formula, const std::string& source = "");

/// Kenward-Roger works on dense (q + p) x (q + p) matrices of the q random effects and p fixed
/// effects, whatever the number of rows (lmm_kr.cpp): more random effects than this are
/// refused (memory grows as q², time as q³; use Satterthwaite there).
constexpr long kKenwardRogerMaxRandomEffects = 3000;

/// A linear combination of the fixed-effect coefficients (by name), tested as lmerTest's
/// contest1D: estimate l'β, its SE and Satterthwaite df.
struct LmmContrast {
  std::string name;
  std::vector<std::pair<std::string, double>> weights;  ///< coefficient name, weight
};

struct LmmOptions {
  bool reml = true;
  int max_evaluations = 20000;  ///< of the profiled deviance, by the optimizer
  /// Kenward-Roger instead of Satterthwaite df (pbkrtest's adjusted cov(β̂) for the SEs and
  /// the scaled F, as lmerTest's ddf = "Kenward-Roger"); REML fits only, at most
  /// kKenwardRogerMaxRandomEffects random effects (Z's columns).
  bool kenward_roger = false;
  /// Contrasts to estimate (Satterthwaite fits only; results in LmmResult::contrasts).
  std::vector<LmmContrast> contrasts;
};

struct LmmCoefficient {
  std::string name;  ///< "(Intercept)", "method1", "method1:texture1", "speed_mps"
  double estimate = 0, se = 0, df = 0, t = 0, p = 0;
};

struct LmmFTest {
  std::string term;  ///< "method", "method:texture"
  double num_df = 0, den_df = 0, F = 0, p = 0;
};

/// One random-effects term: covariance σ² T T' of its coefficients per level of `group`.
struct LmmRandomTerm {
  std::string group;
  int levels = 0;
  std::vector<std::string> names;  ///< "(Intercept)", "method1", ...
  std::vector<double> variance, sd;
  std::vector<std::vector<double>> corr;  ///< correlation matrix (1 on the diagonal)
};

/// A fitted model. Its SolverSummary describes the θ optimisation: converged (the
/// optimizer met its tolerance within max_evaluations), iterations = deviance evaluations,
/// initial_cost/final_cost = the criterion (`deviance`) at lme4's start θ and at the optimum,
/// message = why it stopped.
struct LmmResult : SolverSummary {
  std::string formula;
  bool reml = true;
  int n = 0;                              ///< observations
  std::string ddf;                        ///< "Satterthwaite" or "Kenward-Roger"
  std::vector<LmmCoefficient> fixed;      ///< t tests with `ddf` df (KR: adjusted SEs)
  std::vector<LmmFTest> anova;            ///< type 3, `ddf` df (KR: scaled F)
  std::vector<LmmCoefficient> contrasts;  ///< LmmOptions::contrasts, in their order
  std::vector<LmmRandomTerm> random;      ///< in lme4's order (most levels first)
  std::vector<double> theta;              ///< lme4's θ (lower triangles, column-major)
  double sigma = 0;                       ///< residual SD
  double deviance = 0;  ///< the optimised criterion: REML criterion or ML deviance
  double logLik = 0, AIC = 0, BIC = 0;
  /// Conditional residuals y - Xβ̂ - Zb̂ in the data's row order (R's residuals(lmer)).
  std::vector<double> residuals;
  int n_parameters = 0;  ///< β, θ and σ (lme4's df of logLik)
  // Convergence diagnostics.
  int evaluations = 0;          ///< deviance evaluations (= iterations)
  double gradient_max_abs = 0;  ///< max |∂ deviance / ∂θ| at the optimum (free θ only)
  bool singular = false;        ///< a bounded θ below 1e-4 (lme4's isSingular)
  std::string optimizer;        ///< what ran, for the record
};

/// @param data long table with every formula column as a key column (y is the response)
/// @throws hapticlab::InputError (source, "formula") for a column missing from the table,
///         a factor with one level, or a rank-deficient fixed-effects design
LmmResult FitLmm(const LongTable& data, const std::string& formula, const LmmOptions& options = {});

}  // namespace hapticlab::stats
