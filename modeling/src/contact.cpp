#include "hapticlab/modeling/contact.hpp"

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab::modeling {
namespace {

// One stroke sample projected on the motion axis.
struct Sample {
  double x, v, fn, ff;  // position and velocity along the axis, normal load, friction (along v)
};

std::vector<Sample> Project(const Measurement& m) {
  // Principal axis of the tangential velocity.
  Eigen::Matrix2d c = Eigen::Matrix2d::Zero();
  for (const auto& r : m.rows) c += r.v_mps.head<2>() * r.v_mps.head<2>().transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(c);
  const Eigen::Vector2d u = es.eigenvectors().col(1);
  std::vector<Sample> s;
  for (const auto& r : m.rows) {
    if (!(r.f_N.z() > 0)) continue;  // out of contact
    // The surface's friction on the tool opposes motion: friction along +v is -F.u.
    s.push_back({r.p_m.head<2>().dot(u), r.v_mps.head<2>().dot(u), r.f_N.z(), -r.f_N.head<2>().dot(u)});
  }
  return s;
}

// The discrete Dahl model with viscous term, stepped exactly as the renderer does (1-D).
std::vector<double> SimulateDahl(const std::vector<Sample>& s, double kappa, double mu_k, double mu_b) {
  std::vector<double> out(s.size());
  double fd = 0;
  for (std::size_t t = 0; t < s.size(); ++t) {
    const double fc = mu_k * s[t].fn;
    if (t > 0 && fc > 0) {
      const double dx = s[t].x - s[t - 1].x, len = std::abs(dx);
      if (len > 0) {
        const double target = dx > 0 ? fc : -fc;
        fd = target + (fd - target) * std::exp(-kappa * len / fc);
      }
      if (std::abs(fd) > fc) fd = fd > 0 ? fc : -fc;
    }
    out[t] = fd + mu_b * s[t].v;
  }
  return out;
}

struct DahlResidual {
  const std::vector<Sample>* s;
  bool operator()(const double* const p, double* r) const {
    const auto f = SimulateDahl(*s, p[0], p[1], p[2]);
    for (std::size_t i = 0; i < f.size(); ++i) r[i] = f[i] - (*s)[i].ff;
    return std::isfinite(p[0]) && p[0] > 0 && p[1] > 0;
  }
};

struct HcResidual {
  double d, ddot, f;
  template <typename T>
  bool operator()(const T* const k, const T* const b, const T* const n, T* r) const {
    using std::exp;
    using std::log;
    const T dn = exp(n[0] * log(T(d)));
    r[0] = k[0] * dn + b[0] * dn * T(ddot) - T(f);
    return true;
  }
};

void Covariance(ceres::Problem& problem, std::vector<double*> blocks, std::vector<Estimate*> out) {
  ceres::Covariance::Options co;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> pairs;
  for (auto* b : blocks) pairs.emplace_back(b, b);
  if (!cov.Compute(pairs, &problem)) return;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    double v = 0;
    cov.GetCovarianceBlock(blocks[i], blocks[i], &v);
    out[i]->sd = std::sqrt(std::max(v, 0.0));
  }
}

}  // namespace

void SplitStrokesAndPokes(const Measurement& m, Measurement* strokes, Measurement* pokes) {
  *strokes = m;
  *pokes = m;
  strokes->rows.clear();
  pokes->rows.clear();
  for (const auto& r : m.rows) {
    const bool poke = r.v_mps.head<2>().norm() < 1e-3 && std::abs(r.v_mps.z()) > 1e-4;
    (poke ? pokes : strokes)->rows.push_back(r);
  }
}

DahlFit FitDahl(const Measurement& m, const ContactFitOptions& o) {
  const auto s = Project(m);
  DahlFit fit;
  // Algorithm 1: kappa from pre-sliding samples (eq. 4.9 as least squares), mu_k and mu_b
  // from sliding samples (eq. 4.10, linear least squares), repeated until every parameter
  // changes by less than TC.
  double kappa = 1000, mu_k = 0.3, mu_b = 0;
  for (const auto& x : s) {
    const double v = std::abs(x.v);
    fit.presliding_samples += v <= o.presliding_speed_mps;
    fit.sliding_samples += v >= o.sliding_speed_mps;
  }
  if (fit.sliding_samples < 20 || fit.presliding_samples < 5)
    throw InputError(m.file, 0, "vx_mps",
                     fmt::format("strokes need sliding (>= {:.1f} mm/s) and pre-sliding (<= {:.1f} mm/s) samples; found "
                                 "{} and {}",
                                 o.sliding_speed_mps * 1e3, o.presliding_speed_mps * 1e3, fit.sliding_samples,
                                 fit.presliding_samples));
  for (int pass = 1; pass <= 100; ++pass) {
    // estMu: f_F(t) = mu_b v(t) + mu_k f_n(t-1) sgn(v(t-1)).
    Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
    Eigen::Vector2d b = Eigen::Vector2d::Zero();
    for (std::size_t t = 1; t < s.size(); ++t) {
      if (std::abs(s[t].v) < o.sliding_speed_mps || std::abs(s[t - 1].v) < o.sliding_speed_mps) continue;
      const Eigen::Vector2d a(s[t - 1].fn * (s[t - 1].v > 0 ? 1 : -1), s[t].v);
      A += a * a.transpose();
      b += a * s[t].ff;
    }
    const Eigen::Vector2d mu = A.ldlt().solve(b);
    // estKappa: (y - z) = -kappa (|dx| / f_C) z with z = f_D(t-1) - f_C s, y = f_D(t) - f_C s.
    double num = 0, den = 0;
    for (std::size_t t = 1; t < s.size(); ++t) {
      if (std::abs(s[t].v) > o.presliding_speed_mps) continue;
      const double dx = s[t].x - s[t - 1].x;
      const double fc = mu(0) * s[t - 1].fn;
      if (std::abs(dx) < 1e-12 || !(fc > 0)) continue;
      const double sg = dx > 0 ? 1 : -1;
      const double z = s[t - 1].ff - mu(1) * s[t - 1].v - fc * sg, y = s[t].ff - mu(1) * s[t].v - fc * sg;
      const double w = std::abs(dx) / fc * z;
      num += w * (z - y);
      den += w * w;
    }
    const double k_new = den > 0 ? num / den : kappa;
    const double dk = std::abs(k_new - kappa), dmk = std::abs(mu(0) - mu_k), dmb = std::abs(mu(1) - mu_b);
    kappa = k_new;
    mu_k = mu(0);
    mu_b = mu(1);
    fit.algorithm1_passes = pass;
    if (dk < o.convergence && dmk < o.convergence && dmb < o.convergence) {
      fit.algorithm1_converged = true;
      break;
    }
  }
  // Batch refinement of all three with Ceres on the simulated friction of the whole record.
  double p[3] = {std::max(kappa, 1.0), std::max(mu_k, 1e-3), mu_b};
  ceres::Problem problem;
  auto* cost = new ceres::NumericDiffCostFunction<DahlResidual, ceres::CENTRAL, ceres::DYNAMIC, 3>(
      new DahlResidual{&s}, ceres::TAKE_OWNERSHIP, static_cast<int>(s.size()));
  problem.AddResidualBlock(cost, nullptr, p);
  problem.SetParameterLowerBound(p, 0, 1.0);
  problem.SetParameterLowerBound(p, 1, 1e-4);
  ceres::Solver::Options so;
  so.max_num_iterations = 100;
  so.function_tolerance = 1e-12;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  fit.kappa_N_per_m.value = p[0];
  fit.mu_k.value = p[1];
  fit.mu_b_Ns_per_m.value = p[2];
  // Uncertainties: J^T J of the residuals (numeric) through Ceres' covariance.
  ceres::Covariance::Options co;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> pairs{{p, p}};
  if (cov.Compute(pairs, &problem)) {
    double c[9];
    cov.GetCovarianceBlock(p, p, c);
    fit.kappa_N_per_m.sd = std::sqrt(std::max(c[0], 0.0));
    fit.mu_k.sd = std::sqrt(std::max(c[4], 0.0));
    fit.mu_b_Ns_per_m.sd = std::sqrt(std::max(c[8], 0.0));
  }
  fit.rms_residual_N = std::sqrt(2 * summary.final_cost / static_cast<double>(s.size()));
  return fit;
}

HuntCrossleyFit FitHuntCrossley(const Measurement& m, const ContactFitOptions& o) {
  std::vector<HcResidual> data;
  for (const auto& r : m.rows) {
    const double d = -r.p_m.z();
    if (d > 1e-7 && r.f_N.z() > 0 && r.f_N.z() <= o.max_force_N) data.push_back({d, -r.v_mps.z(), r.f_N.z()});
  }
  if (data.size() < 10)
    throw InputError(m.file, 0, "fz_N", fmt::format("{} poke samples in contact below {:.1f} N; at least 10 are needed",
                                                    data.size(), o.max_force_N));
  // Start: K and n from a log-log fit of quasi-static samples, B = 0.
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const auto& x : data) {
    const double lx = std::log(x.d), ly = std::log(x.f);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  const double nn = static_cast<double>(data.size());
  double n = std::clamp((nn * sxy - sx * sy) / (nn * sxx - sx * sx), 1.0, 2.0);
  double K = std::exp((sy - n * sx) / nn), B = 0;
  ceres::Problem problem;
  for (const auto& x : data)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<HcResidual, 1, 1, 1, 1>(new HcResidual(x)), nullptr, &K, &B, &n);
  problem.SetParameterLowerBound(&K, 0, 1e-9);
  problem.SetParameterLowerBound(&n, 0, 1.0);
  problem.SetParameterUpperBound(&n, 0, 2.0);
  ceres::Solver::Options so;
  so.max_num_iterations = 200;
  so.function_tolerance = 1e-14;
  so.parameter_tolerance = 1e-12;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  HuntCrossleyFit fit;
  fit.K.value = K;
  fit.B.value = B;
  fit.n.value = n;
  fit.samples = static_cast<int>(data.size());
  fit.rms_residual_N = std::sqrt(2 * summary.final_cost / nn);
  Covariance(problem, {&K, &B, &n}, {&fit.K, &fit.B, &fit.n});
  return fit;
}

}  // namespace hapticlab::modeling
