#include "hapticlab/stats/shapiro.hpp"

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/distributions.hpp"

namespace hapticlab::stats {
namespace {

// c[0] + c[1] x + ... + c[n-1] x^(n-1)
double Poly(const double* c, int n, double x) {
  double r = 0;
  for (int i = n - 1; i >= 0; --i) r = r * x + c[i];
  return r;
}

double Qnorm(double p) {
  return boost::math::quantile(boost::math::normal_distribution<double>(), p);
}

// The coefficients a_1..a_{n/2} of W (Royston's polynomial approximations).
std::vector<double> RoystonCoefficients(int n) {
  static const double kC1[] = {0.0, 0.221157, -0.147981, -2.07119, 4.434685, -2.706056};
  static const double kC2[] = {0.0, 0.042981, -0.293762, -1.752461, 5.682633, -3.582633};
  const int half = n / 2;
  std::vector<double> a(static_cast<std::size_t>(half));
  if (n == 3) {
    a[0] = std::sqrt(0.5);
    return a;
  }
  const double an25 = n + 0.25;
  std::vector<double> m(static_cast<std::size_t>(half));
  double summ2 = 0;
  for (int i = 1; i <= half; ++i) {
    m[static_cast<std::size_t>(i - 1)] = Qnorm((i - 0.375) / an25);
    summ2 += m[static_cast<std::size_t>(i - 1)] * m[static_cast<std::size_t>(i - 1)];
  }
  summ2 *= 2;
  const double ssumm2 = std::sqrt(summ2);
  const double rsn = 1.0 / std::sqrt(static_cast<double>(n));
  const double a1 = Poly(kC1, 6, rsn) - m[0] / ssumm2;
  int i1;
  double fac;
  if (n > 5) {
    i1 = 3;
    const double a2 = -m[1] / ssumm2 + Poly(kC2, 6, rsn);
    fac = std::sqrt((summ2 - 2 * m[0] * m[0] - 2 * m[1] * m[1]) / (1 - 2 * a1 * a1 - 2 * a2 * a2));
    a[1] = a2;
  } else {
    i1 = 2;
    fac = std::sqrt((summ2 - 2 * m[0] * m[0]) / (1 - 2 * a1 * a1));
  }
  a[0] = a1;
  for (int i = i1; i <= half; ++i)
    a[static_cast<std::size_t>(i - 1)] = -m[static_cast<std::size_t>(i - 1)] / fac;
  return a;
}

// 1 - W for sorted x: one minus the squared correlation of the data with the full
// (antisymmetric) coefficients, formed directly to keep precision when W is near 1.
double OneMinusW(const std::vector<double>& x, const std::vector<double>& a, double range) {
  const int n = static_cast<int>(x.size()), half = n / 2;
  std::vector<double> af(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < half; ++i) {
    af[static_cast<std::size_t>(i)] = -a[static_cast<std::size_t>(i)];
    af[static_cast<std::size_t>(n - 1 - i)] = a[static_cast<std::size_t>(i)];
  }
  double sa = 0, sx = 0;
  for (int i = 0; i < n; ++i) {
    sa += af[static_cast<std::size_t>(i)];
    sx += x[static_cast<std::size_t>(i)] / range;
  }
  sa /= n;
  sx /= n;
  double ssa = 0, ssx = 0, sax = 0;
  for (int i = 0; i < n; ++i) {
    const double asa = af[static_cast<std::size_t>(i)] - sa;
    const double xsx = x[static_cast<std::size_t>(i)] / range - sx;
    ssa += asa * asa;
    ssx += xsx * xsx;
    sax += asa * xsx;
  }
  const double ssassx = std::sqrt(ssa * ssx);
  return (ssassx - sax) * (ssassx + sax) / (ssa * ssx);
}

// The p-value of W (1 - W = w1): exact for n = 3, Royston's normalizing transformations
// otherwise.
double RoystonP(int n, double W, double w1) {
  if (n == 3)
    return std::max(
        0.0, 6.0 / std::numbers::pi * (std::asin(std::sqrt(W)) - std::asin(std::sqrt(0.75))));
  static const double kG[] = {-2.273, 0.459};
  static const double kC3[] = {0.544, -0.39978, 0.025054, -6.714e-4};
  static const double kC4[] = {1.3822, -0.77857, 0.062767, -0.0020322};
  static const double kC5[] = {-1.5861, -0.31082, -0.083751, 0.0038915};
  static const double kC6[] = {-0.4803, -0.082676, 0.0030302};
  double y = std::log(w1);
  const double xx = std::log(static_cast<double>(n));
  double mean, sd;
  if (n <= 11) {
    const double gamma = Poly(kG, 2, n);
    if (y >= gamma) return 1e-99;  // as R: W is so far from 1 that the approximation breaks down
    y = -std::log(gamma - y);
    mean = Poly(kC3, 4, n);
    sd = std::exp(Poly(kC4, 4, n));
  } else {
    mean = Poly(kC5, 4, xx);
    sd = std::exp(Poly(kC6, 3, xx));
  }
  return PnormUpper((y - mean) / sd);
}

}  // namespace

ShapiroResult ShapiroWilk(std::vector<double> x) {
  const int n = static_cast<int>(x.size());
  if (n < 3 || n > 5000)
    throw InputError("", 0, "values",
                     "Shapiro-Wilk needs 3 to 5000 values, got " + std::to_string(n));
  for (double v : x)
    if (!std::isfinite(v)) throw InputError("", 0, "values", "Shapiro-Wilk: non-finite value");
  std::sort(x.begin(), x.end());
  const double range = x.back() - x.front();
  if (!(range > 1e-10 * std::max(1.0, std::abs(x.front()))))
    throw InputError("", 0, "values", "Shapiro-Wilk: all values are identical");
  const double w1 = OneMinusW(x, RoystonCoefficients(n), range);
  ShapiroResult r;
  r.n = n;
  r.W = 1 - w1;
  r.p = RoystonP(n, r.W, w1);
  return r;
}

}  // namespace hapticlab::stats
