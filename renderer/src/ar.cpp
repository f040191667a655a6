#include "hapticlab/renderer/ar.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "hapticlab/core/status.hpp"

namespace hapticlab::renderer {
namespace {

constexpr double kPi = std::numbers::pi;

// g(w) = e^{j w (p+1)/2} A(e^{jw}). Zeros of Re g are roots of P, zeros of Im g roots of Q.
std::complex<double> G(std::span<const double> c, double w) {
  // A(e^{jw}) = 1 - sum c_i z^i with z = e^{-jw}, by Horner: one sin/cos per frequency.
  const std::size_t p = c.size();
  const std::complex<double> z = std::polar(1.0, -w);
  std::complex<double> h(0.0, 0.0);
  for (std::size_t i = p; i-- > 0;) h = (h + c[i]) * z;
  return (1.0 - h) * std::polar(1.0, w * static_cast<double>(p + 1) / 2.0);
}

// Bisection on one component of g between a and b (sign change known).
double Refine(std::span<const double> c, double a, double b, bool real_part) {
  auto f = [&](double w) { return real_part ? G(c, w).real() : G(c, w).imag(); };
  double fa = f(a);
  for (int it = 0; it < 60; ++it) {
    const double m = 0.5 * (a + b);
    const double fm = f(m);
    if ((fm < 0) == (fa < 0)) {
      a = m;
      fa = fm;
    } else {
      b = m;
    }
  }
  return 0.5 * (a + b);
}

// Multiplies polynomial `poly` (coefficients in z^-1, length n) by (1 + b z^-1 + z^-2) in place.
void MulQuadratic(double* poly, std::size_t& n, double b) {
  poly[n] = 0;
  poly[n + 1] = 0;
  for (std::size_t k = n + 2; k-- > 0;) {
    double v = poly[k];
    if (k >= 1) v += b * poly[k - 1];
    if (k >= 2) v += poly[k - 2];
    poly[k] = v;
  }
  n += 2;
}

}  // namespace

std::vector<double> ArToLsf(std::span<const double> c) {
  const std::size_t p = c.size();
  if (p == 0) return {};
  HL_REQUIRE(IsStableAr(c), "AR filter is not minimum phase: no valid LSFs");
  // Dense scan of (0, pi) for sign changes of Re g and Im g, then bisection.
  const std::size_t n = 512 * (p + 1);
  std::vector<double> lsf;
  lsf.reserve(p);
  double w0 = 1e-9;
  std::complex<double> g0 = G(c, w0);
  for (std::size_t k = 1; k <= n; ++k) {
    const double w1 = k == n ? kPi - 1e-9 : kPi * static_cast<double>(k) / static_cast<double>(n);
    const std::complex<double> g1 = G(c, w1);
    if ((g0.real() < 0) != (g1.real() < 0)) lsf.push_back(Refine(c, w0, w1, true));
    if ((g0.imag() < 0) != (g1.imag() < 0)) lsf.push_back(Refine(c, w0, w1, false));
    w0 = w1;
    g0 = g1;
  }
  std::sort(lsf.begin(), lsf.end());
  if (lsf.size() != p)
    throw std::runtime_error("LSF search found " + std::to_string(lsf.size()) +
                             " frequencies for order " + std::to_string(p));
  return lsf;
}

void LsfToAr(std::span<const double> lsf, std::span<double> c_out,
             std::span<double> work) noexcept {
  // P(z) has the LSFs of odd rank (1st, 3rd, ...), Q(z) those of even rank.
  // Trivial roots: p even -> P has (1 + z^-1), Q has (1 - z^-1); p odd -> Q has (1 - z^-2).
  const std::size_t p = lsf.size();
  double* P = work.data();
  double* Q = work.data() + (p + 3);
  std::size_t np = 1, nq = 1;
  P[0] = 1;
  Q[0] = 1;
  for (std::size_t i = 0; i < p; ++i) {
    if (i % 2 == 0)
      MulQuadratic(P, np, -2.0 * std::cos(lsf[i]));
    else
      MulQuadratic(Q, nq, -2.0 * std::cos(lsf[i]));
  }
  if (p % 2 == 0) {
    // multiply P by (1 + z^-1) and Q by (1 - z^-1)
    P[np] = 0;
    Q[nq] = 0;
    for (std::size_t k = np; k >= 1; --k) P[k] += P[k - 1];
    for (std::size_t k = nq; k >= 1; --k) Q[k] -= Q[k - 1];
    ++np;
    ++nq;
  } else {
    Q[nq] = 0;
    Q[nq + 1] = 0;
    for (std::size_t k = nq + 1; k >= 2; --k) Q[k] -= Q[k - 2];
    nq += 2;
  }
  // A = (P + Q) / 2; c_i = -A_i.
  for (std::size_t i = 1; i <= p; ++i) c_out[i - 1] = -0.5 * (P[i] + Q[i]);
}

std::vector<double> LsfToAr(std::span<const double> lsf) {
  std::vector<double> c(lsf.size()), work(4 * (lsf.size() + 3));
  LsfToAr(lsf, c, work);
  return c;
}

bool IsStableAr(std::span<const double> c) {
  // Step-down (backward Levinson) recursion: stable iff every reflection coefficient |k| < 1.
  std::vector<double> a(c.size() + 1);
  a[0] = 1;
  for (std::size_t i = 0; i < c.size(); ++i) a[i + 1] = -c[i];
  for (std::size_t m = c.size(); m >= 1; --m) {
    const double k = a[m];
    if (!std::isfinite(k) || std::abs(k) >= 1.0) return false;
    const double d = 1.0 - k * k;
    std::vector<double> b(m);
    b[0] = 1;
    for (std::size_t i = 1; i < m; ++i) b[i] = (a[i] - k * a[m - i]) / d;
    a.assign(b.begin(), b.end());
  }
  return true;
}

double ArPsd(std::span<const double> c, double variance, double fs_hz, double f_hz) {
  const double w = 2.0 * kPi * f_hz / fs_hz;
  std::complex<double> a(1.0, 0.0);
  for (std::size_t i = 0; i < c.size(); ++i)
    a -= c[i] * std::polar(1.0, -w * static_cast<double>(i + 1));
  return 2.0 * variance / (fs_hz * std::norm(a));
}

}  // namespace hapticlab::renderer
