#include "hapticlab/stats/distributions.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/special_functions/erf.hpp>
#include <boost/math/tools/roots.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
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

// Chebyshev interpolant of a smooth function on [0, wmax] (160 nodes). The range
// distribution's W(w) and log U(w) are analytic, so this reproduces them to ~1e-14 (checked
// against the direct quadrature in tests/stats/reference_vectors_test.cpp). Used where many
// probabilities share k (a quantile search, a family of Tukey pairs): W is then computed
// 160 times instead of ~250 times per probability.
class Cheb {
 public:
  static constexpr int kN = 160;
  template <class F>
  Cheb(F f, double a, double b) : a_(a), b_(b) {
    std::array<double, kN> v{};
    for (int j = 0; j < kN; ++j) {
      const double x = std::cos(std::numbers::pi * (j + 0.5) / kN);
      v[static_cast<std::size_t>(j)] = f(a + 0.5 * (b - a) * (x + 1));
    }
    for (int i = 0; i < kN; ++i) {
      double sum = 0;
      for (int j = 0; j < kN; ++j) sum += v[static_cast<std::size_t>(j)] * std::cos(std::numbers::pi * i * (j + 0.5) / kN);
      c_[static_cast<std::size_t>(i)] = 2.0 * sum / kN;
    }
  }
  double operator()(double w) const {
    const double x = 2 * (w - a_) / (b_ - a_) - 1;
    double b1 = 0, b2 = 0;  // Clenshaw recurrence
    for (int i = kN - 1; i >= 1; --i) {
      const double b0 = 2 * x * b1 - b2 + c_[static_cast<std::size_t>(i)];
      b2 = b1;
      b1 = b0;
    }
    return x * b1 - b2 + 0.5 * c_[0];
  }

 private:
  double a_, b_;
  std::array<double, kN> c_{};
};

// Beyond 15, 1 - W(w) < k^2 Phi(-15 / sqrt 2) ~ k^2 1e-26: W = 1 to double precision.
constexpr double kLowerWMax = 15.0;
// Beyond 50, U(w) < 1e-260: reported as 0.
constexpr double kUpperWMax = 50.0;

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

double Qtukey(double p, int k, double df) { return TukeyFamily(k, df).Quantile(p); }

}  // namespace hapticlab::stats

namespace hapticlab::stats {

// The median of the range of k normals: below it U = 1 - W is taken from the W table
// (absolute accuracy, U >= 0.5); above it log U is tabulated (relative accuracy for tiny U).
double RangeMedian(int k) {
  double lo = 0, hi = kLowerWMax;
  for (int i = 0; i < 60; ++i) {
    const double m = 0.5 * (lo + hi);
    (RangeLower(m, k) < 0.5 ? lo : hi) = m;
  }
  return 0.5 * (lo + hi);
}

struct TukeyFamily::Tables {
  explicit Tables(int k)
      : median(RangeMedian(k)),
        lower([k](double w) { return RangeLower(w, k); }, 0.0, kLowerWMax),
        log_upper([k](double w) { return std::log(RangeUpper(w, k)); }, median, kUpperWMax) {}
  double median;
  Cheb lower, log_upper;
};

TukeyFamily::TukeyFamily(int k, double df) : k_(k), df_(df) {
  CheckArgs(1.0, k, df);
  tables_ = std::make_shared<Tables>(k);
}

double TukeyFamily::Lower(double q) const {
  const Cheb& w = tables_->lower;
  auto wf = [&w](double x) { return !(x > 0) ? 0.0 : x >= kLowerWMax ? 1.0 : std::clamp(w(x), 0.0, 1.0); };
  if (!(q > 0)) return 0.0;
  if (std::isinf(df_)) return wf(q);
  return std::min(1.0, OuterIntegral(q, df_, wf));
}

double TukeyFamily::Upper(double q) const {
  const Tables& t = *tables_;
  auto uf = [&t](double x) {
    if (!(x > 0)) return 1.0;
    if (x < t.median) return 1.0 - std::clamp(t.lower(x), 0.0, 1.0);
    return x >= kUpperWMax ? 0.0 : std::min(1.0, std::exp(t.log_upper(x)));
  };
  if (!(q > 0)) return 1.0;
  if (std::isinf(df_)) return uf(q);
  return std::min(1.0, OuterIntegral(q, df_, uf));
}

double TukeyFamily::Quantile(double p) const {
  if (!(p > 0 && p < 1)) throw std::invalid_argument("qtukey: p must be in (0, 1)");
  auto f = [&](double q) { return Lower(q) - p; };
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
