#include "hapticlab/stats/distributions.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/special_functions/erf.hpp>
#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hapticlab::stats {
namespace {

namespace bm = boost::math;

double Phi(double x) { return 0.5 * std::erfc(-x / std::numbers::sqrt2); }  // glibc: ~1 ulp
double phi(double x) { return std::exp(-0.5 * x * x) / std::sqrt(2 * std::numbers::pi); }

// Fixed 10-point Gauss-Legendre on each of `pieces` equal subintervals of [a, b]. The
// integrands below are smooth on a scale of ~1 (normal densities), so short pieces give
// ~1e-14 relative accuracy without adaptive error estimation (which, with Boost's
// Gauss-Kronrod at 1e-13, subdivides for seconds without gaining anything).
template <class F>
double Integrate(F f, double a, double b, int pieces) {
  if (!(b > a) || pieces < 1) return 0.0;
  const double h = (b - a) / pieces;
  double total = 0;
  for (int i = 0; i < pieces; ++i)
    total += bm::quadrature::gauss<double, 10>::integrate(f, a + i * h, a + (i + 1) * h);
  return total;
}

// Range distribution of k standard normals: W(w) = P(range < w) and U(w) = 1 - W(w).
// z runs over [-9, 9] (phi(9) ~ 1e-18) or, for U, also around w/2 where its mass sits.
double RangeLower(double w, int k) {
  if (!(w > 0)) return 0.0;
  const int m = k - 1;
  auto f = [&](double z) {
    const double d = Phi(z) - Phi(z - w);
    return d > 0 ? k * phi(z) * std::pow(d, m) : 0.0;
  };
  return std::min(1.0, Integrate(f, -9.0, 9.0, 18));
}

double RangeUpper(double w, int k) {
  if (!(w > 0)) return 1.0;
  const int m = k - 1;
  // a^m - d^m = b * sum_j a^j d^(m-1-j), with a = Phi(z), b = Phi(z - w), d = a - b:
  // no cancellation, so tiny upper tails keep their relative accuracy.
  auto f = [&](double z) {
    const double a = Phi(z), b = Phi(z - w), d = a - b;
    double s = 0, ap = 1;
    for (int j = 0; j < m; ++j) {
      s += ap * std::pow(d, m - 1 - j);
      ap *= a;
    }
    return k * phi(z) * b * s;
  };
  const double lo = std::min(-9.0, 0.5 * w - 9.0), hi = std::max(9.0, 0.5 * w + 9.0);
  return std::min(1.0, Integrate(f, lo, hi, static_cast<int>(std::ceil(hi - lo))));
}

// Density of s = sqrt(chi2_df / df).
double ChiMeanDensity(double s, double df) {
  if (!(s > 0)) return 0.0;
  const double logc = 0.5 * df * std::log(df) - std::lgamma(0.5 * df) - (0.5 * df - 1) * std::log(2.0);
  return std::exp(logc + (df - 1) * std::log(s) - 0.5 * df * s * s);
}

// Outer integral over s: fine pieces across mode +- 10 sd, coarser below and a long
// stretch above (the chi density's right tail is heavy for small df).
template <class Inner>
double OuterIntegral(double q, double df, Inner inner) {
  const double mode = std::sqrt(std::max(df - 1, 0.0) / df);
  const double sd = 1.0 / std::sqrt(2.0 * df);
  auto f = [&](double s) { return ChiMeanDensity(s, df) * inner(q * s); };
  const double a = std::max(0.0, mode - 10 * sd), b = mode + 10 * sd;
  const double far = std::max(2 * b, b + 60 * sd);
  return Integrate(f, 0.0, a, 3) + Integrate(f, a, b, 16) + Integrate(f, b, far, 6);
}

void CheckArgs(double q, int k, double df) {
  if (k < 2) throw std::invalid_argument("ptukey: k must be >= 2, got " + std::to_string(k));
  if (!(df >= 1)) throw std::invalid_argument("ptukey: df must be >= 1, got " + std::to_string(df));
  if (std::isnan(q)) throw std::invalid_argument("ptukey: q is NaN");
}

}  // namespace

double PfUpper(double f, double df1, double df2) {
  if (!(f > 0)) return 1.0;
  return bm::cdf(bm::complement(bm::fisher_f_distribution<double>(df1, df2), f));
}
double Qf(double p, double df1, double df2) {
  return bm::quantile(bm::fisher_f_distribution<double>(df1, df2), p);
}
double PchisqUpper(double x, double df) {
  if (!(x > 0)) return 1.0;
  return bm::cdf(bm::complement(bm::chi_squared_distribution<double>(df), x));
}
double PtTwoSided(double t, double df) {
  return 2 * bm::cdf(bm::complement(bm::students_t_distribution<double>(df), std::abs(t)));
}
double Qt(double p, double df) { return bm::quantile(bm::students_t_distribution<double>(df), p); }
double PnormUpper(double z) { return 0.5 * bm::erfc(z / std::numbers::sqrt2); }
double PnormTwoSided(double z) { return 2 * PnormUpper(std::abs(z)); }

double PtukeyLower(double q, int k, double df) {
  CheckArgs(q, k, df);
  if (!(q > 0)) return 0.0;
  if (std::isinf(df)) return RangeLower(q, k);
  return std::min(1.0, OuterIntegral(q, df, [k](double w) { return RangeLower(w, k); }));
}

double PtukeyUpper(double q, int k, double df) {
  CheckArgs(q, k, df);
  if (!(q > 0)) return 1.0;
  if (std::isinf(df)) return RangeUpper(q, k);
  return std::min(1.0, OuterIntegral(q, df, [k](double w) { return RangeUpper(w, k); }));
}

double Qtukey(double p, int k, double df) {
  if (!(p > 0 && p < 1)) throw std::invalid_argument("qtukey: p must be in (0, 1)");
  auto f = [&](double q) { return PtukeyLower(q, k, df) - p; };
  double lo = 0.0, hi = 4.0;
  while (f(hi) < 0) {
    lo = hi;
    hi *= 2;
    if (hi > 1e6) throw std::runtime_error("qtukey: no root below 1e6");
  }
  std::uintmax_t iters = 200;
  const auto r = bm::tools::toms748_solve(f, lo, hi, bm::tools::eps_tolerance<double>(48), iters);
  return 0.5 * (r.first + r.second);
}

}  // namespace hapticlab::stats
