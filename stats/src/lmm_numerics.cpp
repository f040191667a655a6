// Numerical tools of the LMM fit (lmm_numerics.hpp).

#include "lmm_numerics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hapticlab::stats::lmm_internal {

using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

// Sorts the simplex's vertices by their function values, best first.
void SortSimplex(std::vector<VectorXd>& sx, std::vector<double>& fx) {
  std::vector<std::size_t> o(sx.size());
  for (std::size_t i = 0; i < o.size(); ++i) o[i] = i;
  std::sort(o.begin(), o.end(), [&](auto a, auto b) { return fx[a] < fx[b]; });
  std::vector<VectorXd> s2;
  std::vector<double> f2;
  for (auto i : o) {
    s2.push_back(sx[i]);
    f2.push_back(fx[i]);
  }
  sx = s2;
  fx = f2;
}

// One move of the sorted simplex about the centroid c of all but its worst vertex: reflection,
// expansion, contraction (outside or inside), or a shrink toward the best vertex. `project`
// keeps a point within the bounds; `eval` evaluates (and counts) the function.
template <class Project, class Eval>
void Move(std::vector<VectorXd>& sx, std::vector<double>& fx, const VectorXd& c,
          const Project& project, const Eval& eval) {
  const VectorXd xr = project(c + (c - sx.back()));
  const double fr = eval(xr);
  if (fr < fx.front()) {
    const VectorXd xe = project(c + 2.0 * (c - sx.back()));
    const double fe = eval(xe);
    if (fe < fr) {
      sx.back() = xe;
      fx.back() = fe;
    } else {
      sx.back() = xr;
      fx.back() = fr;
    }
  } else if (fr < fx[fx.size() - 2]) {
    sx.back() = xr;
    fx.back() = fr;
  } else {
    const bool outside = fr < fx.back();
    const VectorXd xc =
        project(outside ? VectorXd(c + 0.5 * (xr - c)) : VectorXd(c + 0.5 * (sx.back() - c)));
    const double fc = eval(xc);
    if (fc < std::min(fr, fx.back())) {
      sx.back() = xc;
      fx.back() = fc;
    } else {
      for (std::size_t i = 1; i < sx.size(); ++i) {
        sx[i] = project(sx[0] + 0.5 * (sx[i] - sx[0]));
        fx[i] = eval(sx[i]);
      }
    }
  }
}

}  // namespace

Minimum NelderMead(const std::function<double(const VectorXd&)>& f, const VectorXd& x0,
                   const std::vector<double>& lower, int max_evals) {
  const Eigen::Index m = x0.size();
  auto project = [&](VectorXd x) {
    for (Eigen::Index i = 0; i < m; ++i) x[i] = std::max(x[i], lower[static_cast<std::size_t>(i)]);
    return x;
  };
  Minimum best{project(x0), 0, 0, false};
  best.f = f(best.x);
  best.evaluations = 1;
  double step = 0.5;
  for (int restart = 0; restart < 30 && best.evaluations < max_evals; ++restart) {
    std::vector<VectorXd> sx{best.x};
    std::vector<double> fx{best.f};
    for (Eigen::Index i = 0; i < m; ++i) {
      VectorXd x = best.x;
      x[i] += (x[i] + step > lower[static_cast<std::size_t>(i)]) ? step : -step;
      sx.push_back(project(x));
      fx.push_back(f(sx.back()));
      ++best.evaluations;
    }
    bool done = false;
    while (best.evaluations < max_evals) {
      SortSimplex(sx, fx);
      double extent = 0;
      for (std::size_t i = 1; i < sx.size(); ++i)
        extent = std::max(extent, (sx[i] - sx[0]).lpNorm<Eigen::Infinity>());
      if (fx.back() - fx.front() <= 1e-12 * (1.0 + std::abs(fx.front())) && extent < 1e-9) {
        done = true;
        break;
      }
      VectorXd c = VectorXd::Zero(m);
      for (std::size_t i = 0; i + 1 < sx.size(); ++i) c += sx[i];
      c /= static_cast<double>(m);
      auto eval = [&](const VectorXd& x) {
        ++best.evaluations;
        return f(x);
      };
      Move(sx, fx, c, project, eval);
    }
    const auto it = std::min_element(fx.begin(), fx.end());
    const double improvement = best.f - *it;
    if (*it < best.f) {
      best.f = *it;
      best.x = sx[static_cast<std::size_t>(it - fx.begin())];
    }
    best.converged = done;
    if (done && restart > 0 && improvement <= 1e-10 * (1.0 + std::abs(best.f))) break;
    step = 1e-3;
  }
  return best;
}

// Richardson extrapolation of a central-difference estimate D(h) whose error is a series in
// h² (numDeriv's method, 4 halvings of the step).
template <class T>
T Richardson(const std::function<T(double)>& D, double h0) {
  constexpr int kLevels = 4;
  std::vector<std::vector<T>> tab(kLevels);
  for (int i = 0; i < kLevels; ++i) {
    tab[static_cast<std::size_t>(i)].push_back(D(h0 / std::pow(2.0, i)));
    for (int k = 1; k <= i; ++k) {
      const auto& a = tab[static_cast<std::size_t>(i)][static_cast<std::size_t>(k - 1)];
      const auto& b = tab[static_cast<std::size_t>(i - 1)][static_cast<std::size_t>(k - 1)];
      const double w = std::pow(4.0, k) - 1.0;
      tab[static_cast<std::size_t>(i)].push_back(T(a + (a - b) / w));
    }
  }
  return tab.back().back();
}

// numDeriv's initial step: 10 % of |x|, 1e-4 near zero.
double Step0(double x) { return 0.1 * std::abs(x) + (std::abs(x) < 1.78e-5 ? 1e-4 : 0.0); }

MatrixXd Hessian(const std::function<double(const VectorXd&)>& f, const VectorXd& x) {
  const Eigen::Index m = x.size();
  const double f0 = f(x);
  MatrixXd H(m, m);
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j <= i; ++j) {
      const double hi0 = Step0(x[i]), hj0 = Step0(x[j]);
      std::function<double(double)> D = [&](double s) {
        const double hi = hi0 * s, hj = hj0 * s;
        VectorXd a = x, b = x;
        if (i == j) {
          a[i] += hi;
          b[i] -= hi;
          return (f(a) - 2.0 * f0 + f(b)) / (hi * hi);
        }
        VectorXd c = x, d = x;
        a[i] += hi, a[j] += hj;
        b[i] += hi, b[j] -= hj;
        c[i] -= hi, c[j] += hj;
        d[i] -= hi, d[j] -= hj;
        return (f(a) - f(b) - f(c) + f(d)) / (4.0 * hi * hj);
      };
      H(i, j) = H(j, i) = Richardson<double>(D, 1.0);
    }
  return H;
}

// d C / d x_i for a matrix-valued C(x), each by Richardson-extrapolated central differences.
std::vector<MatrixXd> Jacobian(const std::function<MatrixXd(const VectorXd&)>& C,
                               const VectorXd& x) {
  std::vector<MatrixXd> J;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double h0 = Step0(x[i]);
    std::function<MatrixXd(double)> D = [&](double s) {
      VectorXd a = x, b = x;
      a[i] += h0 * s;
      b[i] -= h0 * s;
      return MatrixXd((C(a) - C(b)) / (2.0 * h0 * s));
    };
    J.push_back(Richardson<MatrixXd>(D, 1.0));
  }
  return J;
}

}  // namespace hapticlab::stats::lmm_internal
