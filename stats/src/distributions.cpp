#include "hapticlab/stats/distributions.hpp"

#include <algorithm>
#include <array>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/special_functions/erf.hpp>
#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>

#include "hapticlab/core/status.hpp"

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
  // U(w) < k^2 Phi(-w / sqrt 2) < 1e-270 beyond 50: 0 (and no z grid of w/2 pieces).
  if (w >= 50) return 0.0;
  const int m = k - 1;
  // a^m - d^m = b * sum_j a^j d^(m-1-j), with a = Phi(z), b = Phi(z - w), d = a - b:
  // no cancellation, so tiny upper tails keep their relative accuracy.
  auto f = [&](double z) {
    const double a = Phi(z), b = Phi(z - w), d = a - b;
    // S_1 = 1, S_(i+1) = a S_i + d^i gives S_m = sum_j a^j d^(m-1-j) without pow (all
    // terms positive: no cancellation).
    double s = 1, dp = 1;
    for (int i = 1; i < m; ++i) {
      dp *= d;
      s = a * s + dp;
    }
    return k * phi(z) * b * s;
  };
  const double lo = std::min(-9.0, 0.5 * w - 9.0), hi = std::max(9.0, 0.5 * w + 9.0);
  return std::min(1.0, Integrate(f, lo, hi, static_cast<int>(std::ceil(hi - lo))));
}

// Log density of s = sqrt(chi2_df / df).
double LogChiMeanDensity(double s, double df) {
  if (!(s > 0)) return -std::numeric_limits<double>::infinity();
  const double logc =
      0.5 * df * std::log(df) - std::lgamma(0.5 * df) - (0.5 * df - 1) * std::log(2.0);
  return logc + (df - 1) * std::log(s) - 0.5 * df * s * s;
}

// The outer integral P = int_0^inf f_df(s) inner(q s) ds, with log_inner(w) = log inner(w).
// The integrand has two scales: the chi density's (width ~ 1/sqrt(2 df), narrower at small s)
// and the range distribution's (~ 1/q in s, which is what fixed pieces missed for large q and
// small df: issue #24's k = 10, df = 7, q = 27.74). Both factors are log-concave, so the
// integrand is unimodal: its peak s* is found by golden-section search on the log integrand,
// its width h from the curvature there, and Gauss-Legendre panels of width h march out from
// s* on both sides (widening by 1.25 after 8 panels, for heavy tails) until the integrand
// is below e^-60 of its peak or s reaches 0. Relative accuracy ~1e-13 wherever the inner
// function has it (checked against 25-digit quadrature in tests/stats/tukey_accuracy_test.cpp).
template <class Inner, class LogInner>
double OuterIntegral(double q, double df, Inner inner, LogInner log_inner) {
  auto logg = [&](double s) {
    return s > 0 ? LogChiMeanDensity(s, df) + log_inner(q * s) : -INFINITY;
  };
  auto g = [&](double s) {
    return s > 0 ? std::exp(LogChiMeanDensity(s, df)) * inner(q * s) : 0.0;
  };
  const double mode = std::sqrt(std::max(df - 1, 0.0) / df), sd = 1.0 / std::sqrt(2.0 * df);
  // Golden-section search for the maximum of logg on (0, hi].
  double a = 0, b = mode + 40 * sd + 2;
  const double r = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = b - r * (b - a), x2 = a + r * (b - a);
  double f1 = logg(x1), f2 = logg(x2);
  // The peak is needed only to a small fraction of the integrand's width (the panels march
  // out from it until the integrand is negligible on both sides, wherever they start).
  const double tol = 1e-3 * std::min(sd, 1.0 / q);
  for (int i = 0; i < 200 && b - a > tol; ++i) {
    // Both probes on a -inf plateau: the inner function underflowed at large s (the upper
    // tail beyond w = 50), so the mass lies to the left.
    if (f1 > f2 || (std::isinf(f1) && std::isinf(f2))) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - r * (b - a);
      f1 = logg(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + r * (b - a);
      f2 = logg(x2);
    }
  }
  const double s_peak = 0.5 * (a + b);
  const double l_peak = logg(s_peak);
  if (!std::isfinite(l_peak)) return 0.0;
  // Width from the curvature of the log integrand at the peak.
  const double scale = std::min(sd, 1.0 / q);
  double h = 0.5 * scale;
  {
    const double d = std::min(1e-3 * scale, 0.5 * s_peak);
    if (d > 0) {
      const double c = (logg(s_peak + d) - 2 * l_peak + logg(s_peak - d)) / (d * d);
      if (c < 0 && std::isfinite(c)) h = std::min(1.0 / std::sqrt(-c), 2 * scale);
    }
  }
  h = std::max(h, 1e-6 * scale);
  const double stop = l_peak - 60;
  double total = 0;
  // Upward from the peak.
  double s = s_peak, w = h;
  for (int i = 0; i < 4000; ++i) {
    total += bm::quadrature::gauss<double, 10>::integrate(g, s, s + w);
    s += w;
    if (logg(s) < stop) break;
    if (i >= 8) w *= 1.25;
  }
  // Downward to 0.
  s = s_peak;
  w = h;
  for (int i = 0; i < 4000 && s > 0; ++i) {
    const double lo = std::max(0.0, s - w);
    total += bm::quadrature::gauss<double, 10>::integrate(g, lo, s);
    s = lo;
    if (s > 0 && logg(s) < stop) break;
    if (i >= 8) w *= 1.25;
  }
  return total;
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
      for (int j = 0; j < kN; ++j)
        sum += v[static_cast<std::size_t>(j)] * std::cos(std::numbers::pi * i * (j + 0.5) / kN);
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
  HL_REQUIRE(k >= 2, "ptukey: k must be >= 2, got " + std::to_string(k));
  HL_REQUIRE(df >= 1, "ptukey: df must be >= 1, got " + std::to_string(df));
  HL_REQUIRE(!std::isnan(q), "ptukey: q is NaN");
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
  if (std::isinf(x)) return 0.0;  // as R's pchisq(Inf, df, lower.tail = FALSE)
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
  // The smaller tail is integrated directly (the other as its complement), so both keep
  // their relative accuracy.
  const double up = PtukeyUpper(q, k, df);
  if (up <= 0.5) return 1.0 - up;
  auto w = [k](double x) { return RangeLower(x, k); };
  return std::min(1.0, OuterIntegral(q, df, w, [&w](double x) { return std::log(w(x)); }));
}

double PtukeyUpper(double q, int k, double df) {
  CheckArgs(q, k, df);
  if (!(q > 0)) return 1.0;
  if (std::isinf(df)) return RangeUpper(q, k);
  auto u = [k](double x) { return RangeUpper(x, k); };
  return std::min(1.0, OuterIntegral(q, df, u, [&u](double x) { return std::log(u(x)); }));
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
  auto wf = [&w](double x) {
    return !(x > 0) ? 0.0 : x >= kLowerWMax ? 1.0 : std::clamp(w(x), 0.0, 1.0);
  };
  if (!(q > 0)) return 0.0;
  if (std::isinf(df_)) return wf(q);
  // The smaller tail directly, the other as its complement.
  const double up = Upper(q);
  if (up <= 0.5) return 1.0 - up;
  return std::min(1.0, OuterIntegral(q, df_, wf, [&wf](double x) {
                    return std::log(std::max(wf(x), 1e-300));
                  }));
}

double TukeyFamily::Upper(double q) const {
  const Tables& t = *tables_;
  auto log_uf = [&t](double x) {
    if (!(x > 0)) return 0.0;
    if (x < t.median) return std::log1p(-std::clamp(t.lower(x), 0.0, 1.0));
    return x >= kUpperWMax ? -std::numeric_limits<double>::infinity()
                           : std::min(0.0, t.log_upper(x));
  };
  auto uf = [&log_uf](double x) { return std::exp(log_uf(x)); };
  if (!(q > 0)) return 1.0;
  if (std::isinf(df_)) return uf(q);
  return std::min(1.0, OuterIntegral(q, df_, uf, log_uf));
}

double TukeyFamily::Quantile(double p) const {
  HL_REQUIRE(p > 0 && p < 1, "qtukey: p must be in (0, 1)");
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
