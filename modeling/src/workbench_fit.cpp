// Workbench fitting: Ceres for the force channels (numeric derivatives of the replay), ridge
// least squares for the vibration log band powers, cluster-jackknife uncertainties.

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/modeling/contact.hpp"
#include "workbench_internal.hpp"

namespace hapticlab::modeling::wb {

using namespace internal;  // NOLINT(google-build-using-namespace): the workbench's own kernels

// ---------------------------------------------------------------------------------------------
namespace {

constexpr double kVibrationRidge = 1.0;  // see FitVibration
// Clusters of the jackknife covariance: this many consecutive 1 s blocks, so that a cluster spans
// several strokes and rests and the residual's correlation along a stroke stays inside it.
constexpr int kClusterBlocks = 3;

// Ceres functor over one channel's fitted parameters (scaled), replaying the whole channel.
struct ChannelCost {
  Channel channel;
  const Replay* r;
  std::vector<int> idx;  // samples with residuals
  mutable std::vector<Resolved> eff;
  std::vector<std::pair<int, int>> slots;  // (effect, parameter) per unknown
  std::vector<double> scale;
  mutable std::vector<double> ftx, fty;

  void Set(const double* x) const {
    for (std::size_t k = 0; k < slots.size(); ++k)
      eff[slots[k].first].p[slots[k].second] = x[k] * scale[k];
  }
  bool operator()(double const* const* x, double* res) const {
    Set(x[0]);
    if (channel == Channel::kNormal) {
      for (std::size_t k = 0; k < idx.size(); ++k)
        res[k] = NormalForce(eff, r->samples()[idx[k]]) - r->samples()[idx[k]].fn_N;
    } else {
      FrictionForces(eff, *r, ftx.data(), fty.data());
      for (std::size_t k = 0; k < idx.size(); ++k) {
        res[2 * k] = ftx[idx[k]] - r->samples()[idx[k]].ftx_N;
        res[2 * k + 1] = fty[idx[k]] - r->samples()[idx[k]].fty_N;
      }
    }
    for (std::size_t k = 0; k < (channel == Channel::kNormal ? 1 : 2) * idx.size(); ++k)
      if (!std::isfinite(res[k])) return false;
    return true;
  }
};

// Two-sided 97.5 % quantile of Student's t with `dof` degrees of freedom (Cornish-Fisher
// expansion about the normal quantile; within 1e-3 for dof >= 5).
double TQuantile975(int dof) {
  const double z = 1.959963984540054, v = std::max(dof, 1);
  return z + (z * z * z + z) / (4 * v) +
         (5 * std::pow(z, 5) + 16 * z * z * z + 3 * z) / (96 * v * v) +
         (3 * std::pow(z, 7) + 19 * std::pow(z, 5) + 17 * z * z * z - 15 * z) / (384 * v * v * v);
}

FitSummary FromCeres(Channel c, const ceres::Solver::Summary& sum) {
  FitSummary f;
  f.channel = c;
  f.method = "ceres (bounded trust region, numeric derivatives of the replay)";
  switch (sum.termination_type) {
    case ceres::CONVERGENCE:
    case ceres::USER_SUCCESS:
      f.termination = FitTermination::kConverged;
      break;
    case ceres::NO_CONVERGENCE:
      f.termination = FitTermination::kIterationLimit;
      break;
    default:
      f.termination = FitTermination::kFailed;
      break;
  }
  f.message = sum.message;
  f.iterations = sum.num_successful_steps + sum.num_unsuccessful_steps;
  f.initial_cost = sum.initial_cost;
  f.final_cost = sum.final_cost;
  f.converged = f.termination == FitTermination::kConverged;
  f.usable = f.converged && std::isfinite(sum.final_cost);
  return f;
}

// The samples whose residuals a channel's fit takes: in contact and in the split's blocks. The
// normal cap selects by the smoothed load, not the noisy measured force: selecting on the
// response keeps the samples whose noise is negative near the cap and biases the law low.
std::vector<int> FitSamples(const Replay& r, Channel c, const FitOptions& o) {
  std::vector<int> idx;
  for (std::size_t i = 0; i < r.samples().size(); ++i)
    if (r.samples()[i].contact && InSplit(r.samples()[i].block, o.split) &&
        (c != Channel::kNormal || r.samples()[i].fload_N <= o.max_normal_force_N))
      idx.push_back(static_cast<int>(i));
  return idx;
}

// Algorithm 1 starts a friction model that has never been fitted (mu_k, kappa and mu_b at their
// initial values): the Ceres refinement is then the joint batch step of the dissertation.
void StartFromAlgorithmOne(const Replay& r, Split split, std::vector<Resolved>* eff) {
  auto slot = [&](ParamKey key) -> double* {
    for (auto& x : *eff)
      if (x.name == key.effect)
        for (std::size_t k = 0; k < x.specs.size(); ++k)
          if (x.specs[k].name == key.name) return &x.p[k];
    return nullptr;
  };
  auto init = [&](ParamKey key) {
    for (const auto& spec : FindEffect(key.effect)->Params(r))
      if (spec.name == key.name) return spec.init;
    return std::numeric_limits<double>::quiet_NaN();
  };
  double* mu_k = slot(key::kMuK);
  double* kappa = slot(key::kKappa_N_per_m);
  double* mu_b = slot(key::kMuB_Ns_per_m);
  if (!mu_k || !kappa || *mu_k != init(key::kMuK) || *kappa != init(key::kKappa_N_per_m) ||
      (mu_b && *mu_b != init(key::kMuB_Ns_per_m)))
    return;
  try {
    const auto a = AlgorithmOne(r, split);
    if (std::isfinite(a.mu_k) && a.mu_k > 0) *mu_k = std::min(a.mu_k, 3.0);
    if (std::isfinite(a.kappa_N_per_m) && a.kappa_N_per_m > 0)
      *kappa = std::clamp(a.kappa_N_per_m, 10.0, 1e6);
    if (mu_b && std::isfinite(a.mu_b_Ns_per_m)) *mu_b = std::clamp(a.mu_b_Ns_per_m, 0.0, 1000.0);
  } catch (const InputError&) {
    // Too few pre-sliding or sliding samples for Algorithm 1: start from the neutral values.
  }
}

// The fitted parameters as the solver sees them: divided by their scales, started inside their
// bounds. cost->slots and cost->scale get one entry per unknown.
struct Unknowns {
  std::vector<double> x, lo, hi;
};

Unknowns CollectUnknowns(ChannelCost* cost) {
  Unknowns u;
  for (std::size_t e = 0; e < cost->eff.size(); ++e)
    for (std::size_t k = 0; k < cost->eff[e].specs.size(); ++k) {
      const auto& s = cost->eff[e].specs[k];
      if (!s.fitted) continue;
      cost->slots.emplace_back(static_cast<int>(e), static_cast<int>(k));
      cost->scale.push_back(s.scale);
      u.x.push_back(std::clamp(cost->eff[e].p[k], s.lo, s.hi) / s.scale);
      u.lo.push_back(s.lo / s.scale);
      u.hi.push_back(s.hi / s.scale);
    }
  return u;
}

// Ceres' bounded trust region over the channel's nres residuals from u->x; the optimum into
// u->x.
ceres::Solver::Summary SolveChannel(const ChannelCost& cost, int nres, int max_iterations,
                                    Unknowns* u) {
  auto* fn = new ceres::DynamicNumericDiffCostFunction<ChannelCost, ceres::CENTRAL>(
      &cost, ceres::DO_NOT_TAKE_OWNERSHIP);
  fn->AddParameterBlock(static_cast<int>(u->x.size()));
  fn->SetNumResiduals(nres);
  ceres::Problem problem;
  problem.AddResidualBlock(fn, nullptr, u->x.data());
  for (std::size_t k = 0; k < u->x.size(); ++k) {
    problem.SetParameterLowerBound(u->x.data(), static_cast<int>(k), u->lo[k]);
    problem.SetParameterUpperBound(u->x.data(), static_cast<int>(k), u->hi[k]);
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.function_tolerance = 1e-10;
  so.parameter_tolerance = 1e-10;
  so.logging_type = ceres::SILENT;
  so.num_threads = 1;
  ceres::Solver::Summary sum;
  ceres::Solve(so, &problem, &sum);
  return sum;
}

// The optimum into the model (the functor's copy holds the last evaluated point, not the best)
// and one estimate per unknown, its interval the point until the jackknife widens it; those at
// a bound are named in out->summary.at_bounds.
void StoreOptimum(Model* m, const ChannelCost& cost, const Unknowns& u, ChannelFit* out) {
  std::vector<Resolved> eff = cost.eff;
  for (std::size_t k = 0; k < cost.slots.size(); ++k)
    eff[cost.slots[k].first].p[cost.slots[k].second] = u.x[k] * cost.scale[k];
  Store(m, eff);
  for (std::size_t k = 0; k < u.x.size(); ++k) {
    const auto& x_eff = eff[cost.slots[k].first];
    const auto& spec = x_eff.specs[cost.slots[k].second];
    ParamEstimate pe;
    pe.effect = x_eff.name;
    pe.name = spec.name;
    pe.value = u.x[k] * cost.scale[k];
    pe.lo95 = pe.hi95 = pe.value;
    pe.bound_lo = spec.lo;
    pe.bound_hi = spec.hi;
    // At a bound: within 1e-6 of the parameter's range (or of its scale, for open ranges).
    const double tol = 1e-6 * std::max(1.0, std::min(u.hi[k] - u.lo[k], 1e6));
    const bool at_lo = u.x[k] - u.lo[k] <= tol, at_hi = u.hi[k] - u.x[k] <= tol;
    // A bound at exactly zero of a non-negative amplitude (mu_b, B, dmu_s) is its neutral value.
    pe.at_bound = at_hi || (at_lo && u.lo[k] != 0.0);
    if (pe.at_bound)
      out->summary.at_bounds.push_back(fmt::format("{}.{} at its {} bound ({:.6g})", pe.effect,
                                                   pe.name, at_hi ? "upper" : "lower", pe.value));
    out->params.push_back(pe);
  }
}

// The residuals at x (scaled parameters) into *r0 and their central-difference Jacobian.
Eigen::MatrixXd ResidualJacobian(const ChannelCost& cost, const std::vector<double>& x, int nres,
                                 std::vector<double>* r0) {
  Eigen::MatrixXd J(nres, static_cast<Eigen::Index>(x.size()));
  std::vector<double> rp(nres), rm(nres), xs = x;
  const double* xp[1] = {xs.data()};
  r0->assign(nres, 0);
  cost(xp, r0->data());
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double h = 1e-5 * std::max(1.0, std::abs(x[k]));
    std::copy(x.begin(), x.end(), xs.begin());
    xs[k] = x[k] + h;
    cost(xp, rp.data());
    xs[k] = x[k] - h;
    cost(xp, rm.data());
    for (int i = 0; i < nres; ++i) J(i, static_cast<Eigen::Index>(k)) = (rp[i] - rm[i]) / (2 * h);
  }
  return J;
}

// Per cluster of kClusterBlocks blocks: (J_g'J_g, J_g'r_g) of its residuals (`per` a sample).
std::map<int, std::pair<Eigen::MatrixXd, Eigen::VectorXd>> ClusterSums(
    const Replay& r, const std::vector<int>& idx, int per, const Eigen::MatrixXd& J,
    const std::vector<double>& r0) {
  const Eigen::Index np = J.cols();
  std::map<int, std::pair<Eigen::MatrixXd, Eigen::VectorXd>> cl;
  for (Eigen::Index i = 0; i < J.rows(); ++i) {
    const int blk = r.samples()[idx[i / per]].block / kClusterBlocks;
    auto it = cl.try_emplace(blk, Eigen::MatrixXd::Zero(np, np), Eigen::VectorXd::Zero(np)).first;
    it->second.first += J.row(i).transpose() * J.row(i);
    it->second.second += J.row(i).transpose() * r0[static_cast<std::size_t>(i)];
  }
  return cl;
}

// Sandwich covariance over the split's blocks, in scaled parameters, from the Jacobian J of the
// residuals r0 at the optimum, by the cluster (delete-one-cluster) jackknife: the one-step
// Gauss-Newton update d_g = (J'J - J_g'J_g)^-1 J_g' r_g of leaving cluster g out gives cov =
// (G-1)/G sum (d_g - d)(d_g - d)'. The plain CR0 sandwich G/(G-1) (J'J)^-1 sum s_g s_g' (J'J)^-1
// is biased low with the ten clusters of a 30 s recording (it covered the truth in 15-17 of 20
// seeds); the jackknife (CR3, MacKinnon & White 1985; Cameron & Miller 2015, sec. VI) corrects
// for each cluster's leverage. Into out: clusters, covariance (unscaled) and the estimates' SDs
// and t intervals (cut at their bounds: one-sided at a bound). Nothing with fewer than 2.
void JackknifeCovariance(const Replay& r, const ChannelCost& cost, int per,
                         const Eigen::MatrixXd& J, const std::vector<double>& r0, ChannelFit* out) {
  const auto cl = ClusterSums(r, cost.idx, per, J, r0);
  const double G = static_cast<double>(cl.size());
  out->clusters = static_cast<int>(cl.size());
  if (G < 2) return;
  const Eigen::Index npi = J.cols();
  const auto np = static_cast<std::size_t>(npi);
  const Eigen::MatrixXd JtJ = J.transpose() * J;
  std::vector<Eigen::VectorXd> d;
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(npi);
  for (const auto& [blk, a] : cl) {
    d.push_back((JtJ - a.first).completeOrthogonalDecomposition().pseudoInverse() * a.second);
    mean += d.back() / G;
  }
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(npi, npi);
  for (const auto& dg : d) cov += (G - 1) / G * (dg - mean) * (dg - mean).transpose();
  const double t = TQuantile975(out->clusters - 1);
  out->covariance.assign(np * np, 0);
  for (std::size_t a = 0; a < np; ++a)
    for (std::size_t b = 0; b < np; ++b)
      out->covariance[a * np + b] =
          cov(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) * cost.scale[a] *
          cost.scale[b];
  for (std::size_t k = 0; k < np; ++k) {
    auto& pe = out->params[k];
    pe.sd = std::sqrt(std::max(out->covariance[k * np + k], 0.0));
    pe.lo95 = std::max(pe.value - t * pe.sd, pe.bound_lo);
    pe.hi95 = std::min(pe.value + t * pe.sd, pe.bound_hi);
  }
}

ChannelFit FitForceChannel(Model* m, const Replay& r, Channel c, const FitOptions& o) {
  ChannelFit out;
  out.channel = c;
  out.summary.channel = c;
  ChannelCost cost{c, &r, FitSamples(r, c, o), Resolve(*m, r, c), {}, {}, {}, {}};
  if (c == Channel::kFriction && o.algorithm1_init && m->Has(effect::kCoulomb) &&
      m->Has(effect::kDahl))
    StartFromAlgorithmOne(r, o.split, &cost.eff);
  Unknowns u = CollectUnknowns(&cost);
  out.samples = static_cast<int>(cost.idx.size());
  if (u.x.empty() || cost.idx.size() < u.x.size() * 3) {
    out.summary.termination = FitTermination::kNotRun;
    out.summary.not_run = u.x.empty() ? FitNotRun::kNoFittedParameter : FitNotRun::kTooFewSamples;
    out.summary.usable = u.x.empty();
    return out;
  }
  cost.ftx.resize(r.samples().size());
  cost.fty.resize(r.samples().size());
  const int per = c == Channel::kNormal ? 1 : 2;
  const int nres = static_cast<int>(cost.idx.size()) * per;
  out.summary = FromCeres(c, SolveChannel(cost, nres, o.max_iterations, &u));
  StoreOptimum(m, cost, u, &out);
  if (!o.uncertainty) return out;
  std::vector<double> r0;
  const Eigen::MatrixXd J = ResidualJacobian(cost, u.x, nres, &r0);
  JackknifeCovariance(r, cost, per, J, r0, &out);
  return out;
}

ChannelFit FitVibration(Model* m, const Replay& r, Split split) {
  ChannelFit out;
  out.channel = Channel::kVibration;
  out.summary.channel = Channel::kVibration;
  out.summary.method = "linear least squares (ridge on the effect columns)";
  if (!r.has_vibration) {
    out.summary.termination = FitTermination::kNotRun;
    out.summary.not_run = FitNotRun::kNoAcceleration;
    return out;
  }
  const auto vib = Resolve(*m, r, Channel::kVibration);
  std::vector<std::size_t> use;
  for (std::size_t w = 0; w < r.windows.size(); ++w)
    if (InSplit(r.windows[w].block, split)) use.push_back(w);
  int cols = 1;
  for (const auto& x : vib) cols += x.e->VibrationColumns();
  out.samples = static_cast<int>(use.size());
  if (use.size() < static_cast<std::size_t>(cols) + 2) {
    out.summary.termination = FitTermination::kNotRun;
    out.summary.not_run = FitNotRun::kTooFewVibrationWindows;
    return out;
  }
  const std::size_t nb = r.band_lo_hz.size();
  Eigen::MatrixXd X(use.size(), cols);
  Eigen::MatrixXd Y(use.size(), nb);
  for (std::size_t k = 0; k < use.size(); ++k) {
    const auto row = VibrationRow(vib, r.windows[use[k]]);
    for (int c = 0; c < cols; ++c) X(k, c) = row[c];
    for (std::size_t b = 0; b < nb; ++b) Y(k, b) = std::log(r.windows[use[k]].band_power[b]);
  }
  // Ridge on the effect columns (not the intercept): a few dozen windows per band is little
  // data for a dozen coefficients, and exp() turns an over-fitted slope into a large error.
  Eigen::MatrixXd A = X.transpose() * X;
  for (int c = 1; c < cols; ++c) A(c, c) += kVibrationRidge;
  A(0, 0) += 1e-9;
  Eigen::MatrixXd C = A.ldlt().solve(X.transpose() * Y);  // cols x bands
  // ln of a periodogram is biased low (E ln chi2_2/2 = -0.577); set each band's level so the
  // predicted power equals the measured power on average.
  const Eigen::MatrixXd pred = X * C;
  m->coef.clear();
  auto& intercept = m->coef[std::string(effect::kCore)];
  intercept.resize(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    double ratio = 0;
    for (std::size_t k = 0; k < use.size(); ++k) ratio += std::exp(Y(k, b) - pred(k, b));
    intercept[b] = C(0, b) + std::log(ratio / static_cast<double>(use.size()));
  }
  int col = 1;
  for (const auto& x : vib) {
    const int c = x.e->VibrationColumns();
    auto& v = m->coef[x.name];
    v.assign(nb * c, 0);
    for (std::size_t b = 0; b < nb; ++b)
      for (int j = 0; j < c; ++j) v[b * c + j] = C(col + j, b);
    col += c;
  }
  // Predictions are kept within the measured range of each band (plus one e-fold), so an
  // extrapolated condition cannot predict absurd power.
  auto& range_lo = m->coef[std::string(kCoefRangeLo)];
  auto& range_hi = m->coef[std::string(kCoefRangeHi)];
  range_lo.resize(nb);
  range_hi.resize(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    range_lo[b] = Y.col(static_cast<Eigen::Index>(b)).minCoeff() - 1;
    range_hi[b] = Y.col(static_cast<Eigen::Index>(b)).maxCoeff() + 1;
  }
  m->band_edges_hz = r.band_lo_hz;
  m->band_edges_hz.push_back(r.band_hi_hz.back());
  Store(m, vib);
  double sse = 0;
  const Eigen::MatrixXd fitted = X * C;
  for (Eigen::Index k = 0; k < fitted.rows(); ++k)
    for (Eigen::Index b = 0; b < fitted.cols(); ++b) sse += std::pow(Y(k, b) - fitted(k, b), 2);
  out.summary.termination = FitTermination::kConverged;
  out.summary.converged = true;
  out.summary.iterations = 1;
  out.summary.final_cost = 0.5 * sse;
  out.summary.usable = std::isfinite(sse);
  return out;
}

}  // namespace

std::string TerminationText(const FitSummary& s) {
  std::string text(NameOf(kFitTerminationNames, s.termination));
  if (s.termination == FitTermination::kNotRun && s.not_run != FitNotRun::kNone)
    text += " (" + std::string(NameOf(kFitNotRunNames, s.not_run)) + ")";
  return text;
}

FitReport Fit(Model* m, const Replay& r, const FitOptions& o) {
  FitReport rep;
  const std::string core(effect::kCore);
  if (!m->params.count(core))
    for (const auto& s : CoreEffect().Params(r)) m->params[core][s.name] = s.init;
  if (o.normal) rep.channels.push_back(FitForceChannel(m, r, Channel::kNormal, o));
  if (o.friction) rep.channels.push_back(FitForceChannel(m, r, Channel::kFriction, o));
  if (o.vibration && r.has_vibration && !m->vibration_model)
    rep.channels.push_back(FitVibration(m, r, o.split));
  return rep;
}

bool FitReport::IsUsable() const {
  for (const auto& c : channels)
    if (!c.summary.usable) return false;
  return true;
}

const ChannelFit* FitReport::Find(Channel c) const {
  for (const auto& x : channels)
    if (x.channel == c) return &x;
  return nullptr;
}
ChannelFit* FitReport::Find(Channel c) {
  return const_cast<ChannelFit*>(std::as_const(*this).Find(c));
}

}  // namespace hapticlab::modeling::wb
