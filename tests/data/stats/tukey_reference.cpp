// Reference values of the studentized range distribution for
// tests/stats/tukey_accuracy_test.cpp, written independently of stats/src/distributions.cpp
// (own quadrature layout, own Gauss-Legendre nodes), in x87 extended precision (long double,
// 64-bit mantissa, ~19 digits; glibc's erfcl/expl/logl/lgammal), with a 113-bit (__float128,
// libquadmath, ~33 digits) mode for spot checks.
//
//   P(Q > q) = int_0^inf f_df(s) U(q s) ds,
//   U(w) = k int phi(z) Phi(z - w) sum_j Phi(z)^j (Phi(z) - Phi(z - w))^(k-2-j) dz
// (1 - W(w) without cancellation, so tiny tails keep their digits), f_df the density of
// sqrt(chi2_df / df). Inner: Gauss-Legendre panels of width 1.5 over
// [min(-13, w/2 - 13), max(13, w/2 + 13)] (phi(13) ~ 1e-38). Outer: the integrand is
// unimodal; its peak is found by golden-section search, panels of its curvature width march
// out from it until the integrand is below e^-70 of the peak (1e-30). Every value is computed
// with 20 and with 26 nodes per panel; the agreement is written as `digits` (rows under 16
// digits are not written). `tukey_reference K DF Q` prints one value in both precisions;
// tukey_check.py (mpmath, 30 digits, nested tanh-sinh: a different method) checks rows.
// The q of each row is found in double precision so that the upper tail is near a target
// (0.5, 1e-3, 1e-8, 1e-15), then rounded to 6 digits; the reference is for that exact q.
//
// Build and run (a few minutes; SHARD=i/n splits the rows over processes, shard 0 writes
// the header):
//   g++ -O2 -std=c++20 tests/data/stats/tukey_reference.cpp -lquadmath -o /tmp/tukey_reference
//   /tmp/tukey_reference > tests/data/stats/tukey_reference.csv

#include <quadmath.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

using Q = __float128;
using L = long double;

namespace {

// The elementary functions in each precision.
double Erfc(double x) { return std::erfc(x); }
L Erfc(L x) { return erfcl(x); }
Q Erfc(Q x) { return erfcq(x); }
double Exp(double x) { return std::exp(x); }
L Exp(L x) { return expl(x); }
Q Exp(Q x) { return expq(x); }
double Log(double x) { return std::log(x); }
L Log(L x) { return logl(x); }
Q Log(Q x) { return logq(x); }
double Sqrt(double x) { return std::sqrt(x); }
L Sqrt(L x) { return sqrtl(x); }
Q Sqrt(Q x) { return sqrtq(x); }
double Lgamma(double x) { return std::lgamma(x); }
L Lgamma(L x) { return lgammal(x); }
Q Lgamma(Q x) { return lgammaq(x); }
template <class T>
T Pi() {
  return static_cast<T>(acosq(Q(-1)));
}
template <class T>
T Abs(T x) {
  return x < 0 ? -x : x;
}
template <class T>
T Min(T a, T b) {
  return a < b ? a : b;
}
template <class T>
T Max(T a, T b) {
  return a > b ? a : b;
}

template <class T>
T Phi(T x) {
  return Erfc(-x / Sqrt(T(2))) / 2;
}
template <class T>
T phi(T x) {
  return Exp(-x * x / 2) / Sqrt(2 * Pi<T>());
}

template <class T>
struct Nodes {
  std::vector<T> x, w;
  explicit Nodes(int n) {
    // Newton on the Legendre polynomial in 113-bit arithmetic, then rounded to T.
    for (int i = 1; i <= n; ++i) {
      Q z = cosq(acosq(Q(-1)) * (i - Q(0.25)) / (n + Q(0.5)));
      Q dp = 0;
      for (int it = 0; it < 100; ++it) {
        Q p0 = 1, p1 = z;
        for (int j = 2; j <= n; ++j) {
          const Q p2 = ((2 * j - 1) * z * p1 - (j - 1) * p0) / j;
          p0 = p1;
          p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1);
        const Q dz = p1 / dp;
        z -= dz;
        if (fabsq(dz) < Q(1e-33)) break;
      }
      Q p0 = 1, p1 = z;
      for (int j = 2; j <= n; ++j) {
        const Q p2 = ((2 * j - 1) * z * p1 - (j - 1) * p0) / j;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1);
      x.push_back(static_cast<T>(z));
      w.push_back(static_cast<T>(2 / ((1 - z * z) * dp * dp)));
    }
  }
};

template <class T, class F>
T Panel(const F& f, T a, T b, const Nodes<T>& nd) {
  const T h = (b - a) / 2, c = (a + b) / 2;
  T s = 0;
  for (std::size_t i = 0; i < nd.x.size(); ++i) s += nd.w[i] * f(c + h * nd.x[i]);
  return h * s;
}

template <class T>
T U(T w, int k, const Nodes<T>& nd) {
  if (!(w > 0)) return 1;
  // U(100) < k^2 Phi(-100 / sqrt 2) ~ 1e-1087: nothing any tail here could notice.
  if (w > 100) return 0;
  const int m = k - 1;
  auto g = [&](T z) {
    const T a = Phi(z), b = Phi(z - w), d = a - b;
    // S_1 = 1, S_(i+1) = a S_i + d^i gives S_m = sum_j a^j d^(m-1-j).
    T s = 1, dp = 1;
    for (int i = 1; i < m; ++i) {
      dp *= d;
      s = a * s + dp;
    }
    return k * phi(z) * b * s;
  };
  const T lo = Min(T(-13), w / 2 - 13), hi = Max(T(13), w / 2 + 13);
  const int n = static_cast<int>(std::ceil(static_cast<double>((hi - lo) / T(1.5))));
  T t = 0;
  for (int i = 0; i < n; ++i)
    t += Panel(g, lo + (hi - lo) * i / n, lo + (hi - lo) * (i + 1) / n, nd);
  return t;
}

template <class T>
T LogChi(T s, T df) {
  return df / 2 * Log(df) - Lgamma(df / 2) - (df / 2 - 1) * Log(T(2)) + (df - 1) * Log(s) -
         df * s * s / 2;
}

template <class T>
T Upper(T q, int k, double dfd, const Nodes<T>& nd) {
  if (std::isinf(dfd)) return U(q, k, nd);
  const T df = static_cast<T>(dfd);
  auto logg = [&](T s) { return s > 0 ? LogChi(s, df) + Log(U(q * s, k, nd)) : -T(INFINITY); };
  T a = 0, b = Sqrt(Max(df - 1, T(0)) / df) + 40 / Sqrt(2 * df) + 2;
  const T r = (Sqrt(T(5)) - 1) / 2;
  T x1 = b - r * (b - a), x2 = a + r * (b - a), f1 = logg(x1), f2 = logg(x2);
  for (int i = 0; i < 120 && b - a > T(1e-18) * b; ++i) {
    // Both probes where U underflowed (w > 100): the mass lies to the left.
    if (f1 > f2 || (std::isinf(static_cast<double>(f1)) && std::isinf(static_cast<double>(f2)))) {
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
  const T sp = (a + b) / 2, lp = logg(sp);
  const T scale = Min(1 / Sqrt(2 * df), 1 / q);
  T h = scale / 2;
  const T d = Min(scale * T(1e-3), sp / 2);
  if (d > 0) {
    const T c = (logg(sp + d) - 2 * lp + logg(sp - d)) / (d * d);
    if (c < 0) h = Min(1 / Sqrt(-c), 2 * scale);
  }
  auto g = [&](T s) { return s > 0 ? Exp(LogChi(s, df)) * U(q * s, k, nd) : T(0); };
  T total = 0, s = sp, w = h;
  for (int i = 0; i < 100000; ++i) {
    total += Panel(g, s, s + w, nd);
    s += w;
    if (logg(s) < lp - 70) break;
    if (i >= 12) w *= T(1.25);
  }
  s = sp;
  w = h;
  for (int i = 0; i < 100000 && s > 0; ++i) {
    const T lo = Max(T(0), s - w);
    total += Panel(g, lo, s, nd);
    s = lo;
    if (s > 0 && logg(s) < lp - 70) break;
    if (i >= 12) w *= T(1.25);
  }
  return total;
}

std::string Str(Q v, int digits) {
  char buf[128];
  quadmath_snprintf(buf, sizeof buf, "%.*Qe", digits - 1, v);
  return buf;
}

// A q with P(Q > q) within 2 % of target (secant steps on log p against log q, double
// precision), rounded to 6 significant digits.
double FindQ(int k, double df, double target, const Nodes<double>& nd) {
  auto y = [&](double x) { return std::log(Upper(std::exp(x), k, df, nd)) - std::log(target); };
  double x0 = std::log(2.0), x1 = std::log(6.0), y0 = y(x0), y1 = y(x1);
  for (int i = 0; i < 40 && std::abs(y1) > 0.02; ++i) {
    double step = -y1 * (x1 - x0) / (y1 - y0);
    if (!std::isfinite(step)) step = y1 > 0 ? 1 : -1;
    step = std::max(-2.0, std::min(2.0, step));
    x0 = x1;
    y0 = y1;
    x1 += step;
    y1 = y(x1);
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", std::exp(x1));
  return std::stod(buf);
}

}  // namespace

int main(int argc, char** argv) {
  const Nodes<double> nd(12);
  const Nodes<L> la(20), lb(26);
  if (argc == 4) {  // one value: k df q, in long double and in __float128
    const int k = std::atoi(argv[1]);
    const double df = std::string(argv[2]) == "Inf" ? INFINITY : std::atof(argv[2]);
    const Nodes<Q> qa(20);
    std::printf("long double %s\n__float128  %s\n",
                Str(Q(Upper(strtold(argv[3], nullptr), k, df, la)), 20).c_str(),
                Str(Upper(strtoflt128(argv[3], nullptr), k, df, qa), 32).c_str());
    return 0;
  }
  const std::vector<int> ks{2, 3, 5, 10, 20};
  const std::vector<double> dfs{2, 3, 7, 30, INFINITY};
  const std::vector<double> targets{0.5, 1e-3, 1e-8, 1e-15};
  struct P {
    int k;
    double df, q;
  };
  std::vector<std::pair<int, double>> designs;
  for (int k : ks)
    for (double df : dfs) designs.push_back({k, df});
  for (auto d : std::vector<std::pair<int, double>>{{20, 120}, {3, 1000}, {4, 5}, {15, 12}})
    designs.push_back(d);
  std::vector<P> points;
  for (auto [k, df] : designs)
    for (double t : targets) points.push_back({k, df, t});  // q found below, per shard
  points.push_back({10, 7, -27.7407});  // issue #24 (negative: q given, not a target)
  // Optional sharding for two processes: SHARD=i/n keeps points i, i+n, ...
  std::size_t shard = 0, nshards = 1;
  if (const char* sh = std::getenv("SHARD")) std::sscanf(sh, "%zu/%zu", &shard, &nshards);
  if (shard == 0) std::printf("k,df,q,upper,lower,digits\n");
  for (std::size_t i = shard; i < points.size(); i += nshards) {
    P p = points[i];
    p.q = p.q < 0 ? -p.q : FindQ(p.k, p.df, p.q, nd);
    char q[64];
    std::snprintf(q, sizeof q, "%.6g", p.q);
    // The reference is for the decimal q as written (not its nearest double).
    const L ql = strtold(q, nullptr);
    const L ua = Upper(ql, p.k, p.df, la), ub = Upper(ql, p.k, p.df, lb);
    const L rel = Abs(ua - ub) / ub;
    const int digits = rel > 0 ? static_cast<int>(Min(L(19), -log10l(rel))) : 19;
    if (digits < 16) {
      std::fprintf(stderr, "k=%d df=%g q=%.6g: only %d digits, skipped\n", p.k, p.df, p.q, digits);
      continue;
    }
    std::printf("%d,%s,%s,%s,%s,%d\n", p.k,
                std::isinf(p.df) ? "Inf" : std::to_string(static_cast<int>(p.df)).c_str(), q,
                Str(Q(ub), 19).c_str(), Str(Q(1 - ub), 19).c_str(), digits);
    std::fflush(stdout);
  }
}
