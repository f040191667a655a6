// Linear mixed models: lme4's penalised least squares fit and lmerTest's Satterthwaite
// inference (see lmm.hpp for the formulation and references).

#include "hapticlab/stats/lmm.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/distributions.hpp"
#include "lmm_design.hpp"
#include "lmm_numerics.hpp"

namespace hapticlab::stats {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using SpMat = Eigen::SparseMatrix<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// The PLS problem of one model: everything that does not depend on θ is computed once.
class Pls {
 public:
  Pls(const detail::LmmDesign& d, bool reml) : d_(d), reml_(reml) {
    n_ = static_cast<double>(d.y.size());
    p_ = static_cast<double>(d.X.cols());
    ZtZ_ = SpMat(d.Z.transpose() * d.Z);
    ZtX_ = d.Z.transpose() * d.X;
    Zty_ = d.Z.transpose() * d.y;
    XtX_ = d.X.transpose() * d.X;
    Xty_ = d.X.transpose() * d.y;
    // θ layout: per block, the lower triangle of its template, column-major (lme4's).
    for (const auto& b : d.blocks)
      for (int j = 0; j < b.p; ++j)
        for (int i = j; i < b.p; ++i) {
          entries_.push_back({&b - d.blocks.data(), i, j});
          lower_.push_back(i == j ? 0.0 : -std::numeric_limits<double>::infinity());
        }
    eye_.resize(d.Z.cols(), d.Z.cols());
    eye_.setIdentity();
  }

  int ntheta() const { return static_cast<int>(entries_.size()); }
  const std::vector<double>& lower() const { return lower_; }
  double n() const { return n_; }

  struct Solution {
    bool ok = false;
    double ldL2 = 0, ldRX2 = 0, r2 = 0;
    VectorXd beta;
    VectorXd resid;  // conditional residuals y - Xβ - ZΛu
    MatrixXd XtVX;   // R_X'R_X = X'X - X'ZΛ (Λ'Z'ZΛ + I)⁻¹ Λ'Z'X
  };

  Solution Solve(const VectorXd& theta) {
    Solution s;
    const SpMat L = Lambda(theta);
    const SpMat Lt = L.transpose();
    SpMat A = Lt * ZtZ_ * L + eye_;
    chol_.compute(A);
    if (chol_.info() != Eigen::Success) return s;
    const MatrixXd LZX = Lt * ZtX_;
    const VectorXd LZy = Lt * Zty_;
    const MatrixXd S = chol_.solve(LZX);
    const VectorXd sv = chol_.solve(LZy);
    s.XtVX = XtX_ - LZX.transpose() * S;
    Eigen::LLT<MatrixXd> rx(s.XtVX);
    if (rx.info() != Eigen::Success) return s;
    s.beta = rx.solve(Xty_ - LZX.transpose() * sv);
    const VectorXd u = sv - S * s.beta;
    s.resid = d_.y - d_.X * s.beta - d_.Z * (L * u);
    s.r2 = s.resid.squaredNorm() + u.squaredNorm();
    s.ldL2 = chol_.vectorD().array().log().sum();
    s.ldRX2 = 2.0 * rx.matrixLLT().diagonal().array().log().sum();
    s.ok = std::isfinite(s.ldL2) && std::isfinite(s.ldRX2);
    return s;
  }

  // The profiled deviance (REML criterion or ML deviance), lme4's formula.
  double Deviance(const VectorXd& theta) {
    const auto s = Solve(theta);
    if (!s.ok) return std::numeric_limits<double>::infinity();
    if (!reml_) return s.ldL2 + n_ * (1.0 + std::log(kTwoPi * s.r2 / n_));
    const double nmp = n_ - p_;
    return s.ldL2 + s.ldRX2 + nmp * (1.0 + std::log(kTwoPi * s.r2 / nmp));
  }

  // The deviance at given (θ, σ), β at its PLS solution: lmerTest's devfun_vp.
  double DevianceVp(const VectorXd& vp) {
    const VectorXd theta = vp.head(vp.size() - 1);
    const double s2 = vp[vp.size() - 1] * vp[vp.size() - 1];
    const auto s = Solve(theta);
    if (!s.ok) return std::numeric_limits<double>::quiet_NaN();
    double dev = s.ldL2 + s.r2 / s2 + n_ * std::log(kTwoPi * s2);
    if (reml_) dev += s.ldRX2 - p_ * std::log(kTwoPi * s2);
    return dev;
  }

  // cov(β̂) = σ² (R_X'R_X)⁻¹ at (θ, σ).
  MatrixXd CovBeta(const VectorXd& vp) {
    const auto s = Solve(vp.head(vp.size() - 1));
    const double s2 = vp[vp.size() - 1] * vp[vp.size() - 1];
    return s2 * s.XtVX.inverse();
  }

  // The block's template T (relative covariance factor) from θ.
  MatrixXd Template(const VectorXd& theta, std::size_t block) const {
    const int p = d_.blocks[block].p;
    MatrixXd T = MatrixXd::Zero(p, p);
    for (std::size_t t = 0; t < entries_.size(); ++t)
      if (static_cast<std::size_t>(entries_[t].block) == block)
        T(entries_[t].i, entries_[t].j) = theta[static_cast<Eigen::Index>(t)];
    return T;
  }

 private:
  SpMat Lambda(const VectorXd& theta) const {
    std::vector<Eigen::Triplet<double>> trip;
    for (std::size_t t = 0; t < entries_.size(); ++t) {
      const auto& e = entries_[t];
      const auto& b = d_.blocks[static_cast<std::size_t>(e.block)];
      for (int l = 0; l < b.levels; ++l)
        trip.emplace_back(b.offset + l * b.p + e.i, b.offset + l * b.p + e.j,
                          theta[static_cast<Eigen::Index>(t)]);
    }
    SpMat L(d_.Z.cols(), d_.Z.cols());
    L.setFromTriplets(trip.begin(), trip.end());
    return L;
  }

  struct Entry {
    std::ptrdiff_t block;
    int i, j;
  };
  const detail::LmmDesign& d_;
  bool reml_;
  double n_ = 0, p_ = 0;
  SpMat ZtZ_, eye_;
  MatrixXd ZtX_, XtX_;
  VectorXd Zty_, Xty_;
  std::vector<Entry> entries_;
  std::vector<double> lower_;
  Eigen::SimplicialLDLT<SpMat> chol_;
};

using lmm_internal::Hessian;
using lmm_internal::Jacobian;
using lmm_internal::Minimum;
using lmm_internal::NelderMead;

// lmerTest's get_Fstat_ddf: the F denominator df from the per-direction df.
double FStatDdf(const std::vector<double>& nu) {
  if (nu.size() == 1) return nu[0];
  bool equal = true;
  for (std::size_t i = 1; i < nu.size(); ++i) equal = equal && std::abs(nu[i] - nu[i - 1]) < 1e-8;
  if (equal) {
    double s = 0;
    for (double v : nu) s += v;
    return s / static_cast<double>(nu.size());
  }
  double E = 0;
  for (double v : nu) {
    if (v <= 2) return 2;
    E += v / (v - 2);
  }
  return 2 * E / (E - static_cast<double>(nu.size()));
}

// Kenward-Roger t and F tests (lmerTest's ddf = "Kenward-Roger", through pbkrtest).
// The hypothesis matrix of a fixed term: one row per coefficient of the term, selecting it
// among the p coefficients (with sum-to-zero contrasts, lmerTest's type 3 contrasts).
MatrixXd Selector(const std::vector<int>& columns, Eigen::Index p) {
  MatrixXd L = MatrixXd::Zero(static_cast<Eigen::Index>(columns.size()), p);
  for (std::size_t i = 0; i < columns.size(); ++i)
    L(static_cast<Eigen::Index>(i), columns[i]) = 1.0;
  return L;
}

void KenwardRoger(const detail::LmmDesign& d, const MatrixXd& Phi, const VectorXd& beta,
                  LmmResult& r) {
  std::vector<double> gamma;
  for (const auto& t : r.random) {
    const auto k = t.names.size();
    for (std::size_t j = 0; j < k; ++j)
      for (std::size_t i = j; i < k; ++i)
        gamma.push_back(i == j ? t.variance[i] : t.corr[i][j] * t.sd[i] * t.sd[j]);
  }
  for (double& g : gamma)
    if (!std::isfinite(g)) g = 0;  // a correlation with a zero variance: the covariance is 0
  gamma.push_back(r.sigma * r.sigma);
  const auto a = detail::KenwardRogerVcov(d, gamma, Phi);
  const Eigen::Index p = Phi.rows();
  for (Eigen::Index j = 0; j < p; ++j) {
    LmmCoefficient c;
    c.name = d.x_names[static_cast<std::size_t>(j)];
    c.estimate = beta[j];
    c.se = std::sqrt(a.PhiA(j, j));
    c.t = c.estimate / c.se;
    c.df = detail::KenwardRogerTest(a, Phi, MatrixXd(VectorXd::Unit(p, j).transpose()), beta).ddf;
    c.p = PtTwoSided(c.t, c.df);
    r.fixed.push_back(c);
  }
  for (const auto& term : d.x_terms) {
    const MatrixXd L = Selector(term.columns, p);
    const Eigen::Index q = L.rows();
    const auto kt = detail::KenwardRogerTest(a, Phi, L, beta);
    LmmFTest t;
    t.term = term.name;
    t.num_df = static_cast<double>(q);
    t.den_df = kt.ddf;
    t.F = kt.F;
    t.p = PfUpper(t.F, t.num_df, t.den_df);
    r.anova.push_back(t);
  }
}

// What FitLmm refuses before fitting: missing responses, a rank-deficient fixed design, no
// residual df, and a Kenward-Roger request it cannot serve.
void CheckLmmInput(const LongTable& data, const LmmFormula& f, const detail::LmmDesign& d,
                   const LmmOptions& options) {
  for (double v : data.y)
    if (!std::isfinite(v))
      throw InputError(data.source, 0, f.response, "missing response values are not supported");
  const Eigen::Index p = d.X.cols();
  {
    Eigen::ColPivHouseholderQR<MatrixXd> qr(d.X);
    if (qr.rank() < p)
      throw InputError(data.source, 0, "formula",
                       "the fixed-effects design is rank deficient (rank " +
                           std::to_string(qr.rank()) + " < " + std::to_string(p) +
                           " columns): a cell of the design has no data?");
  }
  if (d.X.rows() <= p)
    throw InputError(data.source, 0, "formula", "fewer observations than fixed effects");
  if (options.kenward_roger && !options.reml)
    throw InputError(
        data.source, 0, "ddf",
        "Kenward-Roger needs a REML fit (as lmerTest and pbkrtest), not a maximum-likelihood one");
  if (options.kenward_roger && d.Z.cols() > kKenwardRogerMaxRandomEffects)
    throw InputError(
        data.source, 0, "ddf",
        "Kenward-Roger works on dense matrices of the random effects; this model has " +
            std::to_string(d.Z.cols()) + " (more than " +
            std::to_string(kKenwardRogerMaxRandomEffects) +
            "): use Satterthwaite df (--ddf satterthwaite)");
}

// θ̂: the profiled deviance minimised by Nelder-Mead from lme4's start (1 on the diagonals, 0
// off them). Fills the optimizer's fields of r.
VectorXd FitTheta(Pls& pls, const LmmOptions& options, LmmResult& r) {
  VectorXd theta0(pls.ntheta());
  for (int t = 0; t < pls.ntheta(); ++t)
    theta0[t] = pls.lower()[static_cast<std::size_t>(t)] == 0.0 ? 1.0 : 0.0;
  auto dev = [&](const VectorXd& th) { return pls.Deviance(th); };
  r.initial_cost = dev(theta0);
  const Minimum opt = NelderMead(dev, theta0, pls.lower(), options.max_evaluations);
  r.optimizer = "Nelder-Mead with bounds, restarted to convergence";
  r.evaluations = opt.evaluations;
  r.iterations = opt.evaluations;
  r.converged = opt.converged;
  r.final_cost = opt.f;
  r.message = opt.converged ? "converged: a restart no longer improved the deviance"
                            : "stopped at max_evaluations (" +
                                  std::to_string(options.max_evaluations) + ") before converging";
  r.theta.assign(opt.x.data(), opt.x.data() + opt.x.size());
  r.deviance = opt.f;
  return opt.x;
}

// Diagnostics: gradient over the free θ, singular fit (lme4's isSingular, tol 1e-4).
void CheckTheta(Pls& pls, const VectorXd& theta, LmmResult& r) {
  auto dev = [&](const VectorXd& th) { return pls.Deviance(th); };
  for (int t = 0; t < pls.ntheta(); ++t) {
    const bool bounded = pls.lower()[static_cast<std::size_t>(t)] == 0.0;
    if (bounded && theta[t] < 1e-4) {
      r.singular = true;
      continue;
    }
    const double h = 1e-6 * std::max(1.0, std::abs(theta[t]));
    VectorXd a = theta, b = theta;
    a[t] += h;
    b[t] -= h;
    r.gradient_max_abs = std::max(r.gradient_max_abs, std::abs(dev(a) - dev(b)) / (2 * h));
  }
}

// σ, the residuals and the information criteria at the PLS solution of θ̂.
void FitStatistics(const Pls::Solution& sol, double n, Eigen::Index p, int ntheta, bool reml,
                   LmmResult& r) {
  r.sigma = std::sqrt(sol.r2 / (reml ? n - static_cast<double>(p) : n));
  r.residuals.assign(sol.resid.data(), sol.resid.data() + sol.resid.size());
  r.logLik = -0.5 * r.deviance;
  r.n_parameters = static_cast<int>(p) + ntheta + 1;
  r.AIC = -2.0 * r.logLik + 2.0 * r.n_parameters;
  r.BIC = -2.0 * r.logLik + std::log(n) * r.n_parameters;
}

// Block k's variances, standard deviations and correlations, σ² T T' (lme4's VarCorr).
LmmRandomTerm RandomTerm(const detail::LmmDesign& d, const Pls& pls, const VectorXd& theta,
                         std::size_t k, double sigma) {
  const auto& b = d.blocks[k];
  const MatrixXd T = pls.Template(theta, k);
  const MatrixXd S = sigma * sigma * T * T.transpose();
  LmmRandomTerm rt;
  rt.group = b.group;
  // A grouping factor named again is "g.1", "g.2" (as lme4's VarCorr names it).
  const auto again = std::count_if(d.blocks.begin(), d.blocks.begin() + static_cast<long>(k),
                                   [&](const auto& o) { return o.group == b.group; });
  if (again > 0) rt.group += "." + std::to_string(again);
  rt.levels = b.levels;
  rt.names = b.names;
  for (int i = 0; i < b.p; ++i) {
    rt.variance.push_back(S(i, i));
    rt.sd.push_back(std::sqrt(S(i, i)));
  }
  rt.corr.assign(static_cast<std::size_t>(b.p),
                 std::vector<double>(static_cast<std::size_t>(b.p), 1.0));
  for (int i = 0; i < b.p; ++i)
    for (int j = 0; j < b.p; ++j)
      if (i != j) {
        const double den = std::sqrt(S(i, i) * S(j, j));
        rt.corr[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] =
            den > 0 ? S(i, j) / den : std::numeric_limits<double>::quiet_NaN();
      }
  return rt;
}

// Satterthwaite's df (lmerTest): A = 2 H⁻¹ over (θ, σ); J_i = ∂cov(β̂)/∂(θ, σ)_i; C = cov(β̂).
struct SatterthwaiteDf {
  SatterthwaiteDf(Pls& pls, const VectorXd& vp) {
    const MatrixXd H = Hessian([&](const VectorXd& x) { return pls.DevianceVp(x); }, vp);
    A = 2.0 * H.inverse();
    C = pls.CovBeta(vp);
    J = Jacobian([&](const VectorXd& x) { return pls.CovBeta(x); }, vp);
  }

  // The df of l'β̂, whose variance is var.
  double Df(const VectorXd& l, double var) const {
    VectorXd g(static_cast<Eigen::Index>(J.size()));
    for (std::size_t i = 0; i < J.size(); ++i) g[static_cast<Eigen::Index>(i)] = l.dot(J[i] * l);
    return 2.0 * var * var / g.dot(A * g);
  }

  MatrixXd A, C;
  std::vector<MatrixXd> J;
};

// t tests of the coefficients.
void SatterthwaiteFixed(const detail::LmmDesign& d, const VectorXd& beta, const SatterthwaiteDf& s,
                        LmmResult& r) {
  const Eigen::Index p = d.X.cols();
  for (Eigen::Index j = 0; j < p; ++j) {
    LmmCoefficient c;
    c.name = d.x_names[static_cast<std::size_t>(j)];
    c.estimate = beta[j];
    c.se = std::sqrt(s.C(j, j));
    c.t = c.estimate / c.se;
    c.df = s.Df(VectorXd::Unit(p, j), s.C(j, j));
    c.p = PtTwoSided(c.t, c.df);
    r.fixed.push_back(c);
  }
}

// t tests of the requested contrasts (weights on named coefficients).
void SatterthwaiteContrasts(const LongTable& data, const detail::LmmDesign& d,
                            const LmmOptions& options, const VectorXd& beta,
                            const SatterthwaiteDf& s, LmmResult& r) {
  const Eigen::Index p = d.X.cols();
  for (const auto& con : options.contrasts) {
    VectorXd l = VectorXd::Zero(p);
    for (const auto& [name, w] : con.weights) {
      const auto at = std::find(d.x_names.begin(), d.x_names.end(), name);
      if (at == d.x_names.end())
        throw InputError(data.source, 0, "formula",
                         "contrast '" + con.name + "' names no coefficient '" + name + "'");
      l[at - d.x_names.begin()] += w;
    }
    LmmCoefficient c;
    c.name = con.name;
    c.estimate = l.dot(beta);
    const double var = l.dot(s.C * l);
    c.se = std::sqrt(var);
    c.t = c.estimate / c.se;
    c.df = s.Df(l, var);
    c.p = PtTwoSided(c.t, c.df);
    r.contrasts.push_back(c);
  }
}

// Type 3 F tests: with sum-to-zero contrasts and every cell observed, the hypothesis of a
// term is that its coefficients are zero (L selects them), as lmerTest's type 3 contrasts.
void SatterthwaiteAnova(const detail::LmmDesign& d, const VectorXd& beta, const SatterthwaiteDf& s,
                        LmmResult& r) {
  for (const auto& term : d.x_terms) {
    const MatrixXd L = Selector(term.columns, d.X.cols());
    const Eigen::Index q = L.rows();
    Eigen::SelfAdjointEigenSolver<MatrixXd> eig(L * s.C * L.transpose());
    const MatrixXd PtL = eig.eigenvectors().transpose() * L;
    std::vector<double> nu;
    double F = 0;
    for (Eigen::Index m = 0; m < q; ++m) {
      const double dm = eig.eigenvalues()[m];
      const VectorXd l = PtL.row(m).transpose();
      F += std::pow(l.dot(beta), 2) / dm;
      nu.push_back(s.Df(l, dm));
    }
    LmmFTest t;
    t.term = term.name;
    t.num_df = static_cast<double>(q);
    t.F = F / static_cast<double>(q);
    t.den_df = FStatDdf(nu);
    t.p = PfUpper(t.F, t.num_df, t.den_df);
    r.anova.push_back(t);
  }
}

}  // namespace

LmmResult FitLmm(const LongTable& data, const std::string& formula, const LmmOptions& options) {
  const LmmFormula f = ParseLmmFormula(formula, data.source);
  const detail::LmmDesign d = detail::BuildLmmDesign(data, f);
  CheckLmmInput(data, f, d, options);
  Pls pls(d, options.reml);
  LmmResult r;
  r.formula = formula;
  r.reml = options.reml;
  r.ddf = options.kenward_roger ? "Kenward-Roger" : "Satterthwaite";
  r.n = static_cast<int>(d.y.size());
  const VectorXd theta = FitTheta(pls, options, r);
  CheckTheta(pls, theta, r);
  const auto sol = pls.Solve(theta);
  FitStatistics(sol, pls.n(), d.X.cols(), pls.ntheta(), options.reml, r);
  for (std::size_t k = 0; k < d.blocks.size(); ++k)
    r.random.push_back(RandomTerm(d, pls, theta, k, r.sigma));

  VectorXd vp(pls.ntheta() + 1);
  vp << theta, r.sigma;
  if (options.kenward_roger) {
    KenwardRoger(d, pls.CovBeta(vp), sol.beta, r);
    return r;
  }
  const SatterthwaiteDf s(pls, vp);
  SatterthwaiteFixed(d, sol.beta, s, r);
  SatterthwaiteContrasts(data, d, options, sol.beta, s, r);
  SatterthwaiteAnova(d, sol.beta, s, r);
  return r;
}

}  // namespace hapticlab::stats
