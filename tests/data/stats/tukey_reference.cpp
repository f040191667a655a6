// High-precision reference values of the studentized range distribution, in 113-bit
// (__float128, ~33 significant digits) arithmetic with libquadmath: tukey_reference.csv for
// tests/stats/tukey_accuracy_test.cpp. Independent of stats/src/distributions.cpp (own
// quadrature layout, own nodes, quad precision throughout).
//
//   P(Q > q) = int_0^inf f_df(s) U(q s) ds,
//   U(w) = k int phi(z) Phi(z - w) sum_j Phi(z)^j (Phi(z) - Phi(z - w))^(k-2-j) dz
// (1 - W(w) without cancellation), f_df the density of sqrt(chi2_df / df). Inner: Gauss-
// Legendre panels of width 1 over [min(-13, w/2 - 13), max(13, w/2 + 13)] (phi(13) ~ 1e-38).
// Outer: the integrand is unimodal; its peak is found by golden-section search, panels of
// its curvature width march out from it until the integrand is below e^-70 of the peak.
// Every value is computed with 20 and with 28 nodes per panel (outer panels also halved) and
// the agreement is written as `digits`; rows under 20 digits are not written.
// tukey_check.py (mpmath, 30 digits, nested tanh-sinh) checks selected rows independently.
//
// Build and run (about 30 min of CPU; SHARD=i/n splits the points over processes, the
// first shard writes the header):
//   g++ -O2 -std=c++20 tests/data/stats/tukey_reference.cpp -lquadmath -o /tmp/tukey_reference
//   /tmp/tukey_reference > tests/data/stats/tukey_reference.csv
//   /tmp/tukey_reference K DF Q    (one value, both node counts)

#include <quadmath.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

using R = __float128;

namespace {

const R kSqrt2 = sqrtq(R(2));
const R kPi = acosq(R(-1));

R Phi(R x) { return erfcq(-x / kSqrt2) / 2; }
R phi(R x) { return expq(-x * x / 2) / sqrtq(2 * kPi); }

struct Nodes {
  std::vector<R> x, w;
  explicit Nodes(int n) {
    for (int i = 1; i <= n; ++i) {
      R z = cosq(kPi * (i - R(0.25)) / (n + R(0.5)));
      R dp = 0;
      for (int it = 0; it < 100; ++it) {
        R p0 = 1, p1 = z;
        for (int j = 2; j <= n; ++j) {
          const R p2 = ((2 * j - 1) * z * p1 - (j - 1) * p0) / j;
          p0 = p1;
          p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1);
        const R dz = p1 / dp;
        z -= dz;
        if (fabsq(dz) < R(1e-34)) break;
      }
      R p0 = 1, p1 = z;
      for (int j = 2; j <= n; ++j) {
        const R p2 = ((2 * j - 1) * z * p1 - (j - 1) * p0) / j;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1);
      x.push_back(z);
      w.push_back(2 / ((1 - z * z) * dp * dp));
    }
  }
};

template <class F>
R Panel(const F& f, R a, R b, const Nodes& nd) {
  const R h = (b - a) / 2, c = (a + b) / 2;
  R s = 0;
  for (std::size_t i = 0; i < nd.x.size(); ++i) s += nd.w[i] * f(c + h * nd.x[i]);
  return h * s;
}

R U(R w, int k, const Nodes& nd) {
  if (!(w > 0)) return 1;
  const int m = k - 1;
  auto g = [&](R z) {
    const R a = Phi(z), b = Phi(z - w), d = a - b;
    // S_1 = 1, S_(i+1) = a S_i + d^i gives S_m = sum_j a^j d^(m-1-j).
    R s = 1, dp = 1;
    for (int i = 1; i < m; ++i) {
      dp *= d;
      s = a * s + dp;
    }
    return k * phi(z) * b * s;
  };
  const R lo = fminq(-13, w / 2 - 13), hi = fmaxq(13, w / 2 + 13);
  const int n = static_cast<int>(ceilq(hi - lo));
  R t = 0;
  for (int i = 0; i < n; ++i) t += Panel(g, lo + (hi - lo) * i / n, lo + (hi - lo) * (i + 1) / n, nd);
  return t;
}

R LogChi(R s, R df) {
  return df / 2 * logq(df) - lgammaq(df / 2) - (df / 2 - 1) * logq(R(2)) + (df - 1) * logq(s) - df * s * s / 2;
}

// refine: 1 = base panels, 2 = halved outer panels
R Upper(R q, int k, R df, const Nodes& nd, int refine) {
  if (isinfq(df)) return U(q, k, nd);
  auto logg = [&](R s) { return s > 0 ? LogChi(s, df) + logq(U(q * s, k, nd)) : R(-1e300); };
  // golden section for the peak
  R a = 0, b = sqrtq(fmaxq(df - 1, 0) / df) + 40 / sqrtq(2 * df) + 2;
  const R r = (sqrtq(R(5)) - 1) / 2;
  R x1 = b - r * (b - a), x2 = a + r * (b - a), f1 = logg(x1), f2 = logg(x2);
  for (int i = 0; i < 110 && b - a > R(1e-25) * b; ++i) {
    if (f1 > f2) {
      b = x2; x2 = x1; f2 = f1; x1 = b - r * (b - a); f1 = logg(x1);
    } else {
      a = x1; x1 = x2; f1 = f2; x2 = a + r * (b - a); f2 = logg(x2);
    }
  }
  const R sp = (a + b) / 2, lp = logg(sp);
  const R scale = fminq(1 / sqrtq(2 * df), 1 / q);
  R h = scale / 2;
  const R d = fminq(scale * R(1e-4), sp / 2);
  if (d > 0) {
    const R c = (logg(sp + d) - 2 * lp + logg(sp - d)) / (d * d);
    if (c < 0) h = fminq(1 / sqrtq(-c), 2 * scale);
  }
  h /= refine;
  auto g = [&](R s) { return s > 0 ? expq(LogChi(s, df)) * U(q * s, k, nd) : R(0); };
  R total = 0, s = sp, w = h;
  for (int i = 0; i < 100000; ++i) {
    total += Panel(g, s, s + w, nd);
    s += w;
    if (logg(s) < lp - 70) break;
    if (i >= 12 * refine) w *= 1 + R(0.25) / refine;
  }
  s = sp;
  w = h;
  for (int i = 0; i < 100000 && s > 0; ++i) {
    const R lo = fmaxq(0, s - w);
    total += Panel(g, lo, s, nd);
    s = lo;
    if (s > 0 && logg(s) < lp - 70) break;
    if (i >= 12 * refine) w *= 1 + R(0.25) / refine;
  }
  return total;
}

std::string Str(R v, int digits = 25) {
  char buf[128];
  quadmath_snprintf(buf, sizeof buf, "%.*Qe", digits - 1, v);
  return buf;
}

// A q with P(Q > q) within 5 % of target (secant steps on log p against log q, coarse
// nodes), rounded to 6 significant digits: the reference is then computed for that exact q.
double FindQ(int k, double df, double target, const Nodes& coarse) {
  auto y = [&](double x) {
    return std::log(static_cast<double>(Upper(R(std::exp(x)), k, R(df), coarse, 1))) - std::log(target);
  };
  double x0 = std::log(2.0), x1 = std::log(6.0), y0 = y(x0), y1 = y(x1);
  for (int i = 0; i < 30 && std::abs(y1) > 0.05; ++i) {
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
  const Nodes coarse(8), a(20), b(28);
  if (argc == 4) {  // one value: k df q
    const int k = std::atoi(argv[1]);
    const double df = std::string(argv[2]) == "Inf" ? INFINITY : std::atof(argv[2]);
    const R q = strtoflt128(argv[3], nullptr);
    std::printf("%s\n%s\n", Str(Upper(q, k, R(df), a, 1), 30).c_str(), Str(Upper(q, k, R(df), b, 2), 30).c_str());
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
  for (auto d : std::vector<std::pair<int, double>>{{20, 120}, {3, 1000}, {4, 5}, {15, 12}}) designs.push_back(d);
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
    p.q = p.q < 0 ? -p.q : FindQ(p.k, p.df, p.q, coarse);
    const R ua = Upper(R(p.q), p.k, R(p.df), a, 1), ub = Upper(R(p.q), p.k, R(p.df), b, 2);
    const R rel = fabsq(ua - ub) / ub;
    const int digits = rel > 0 ? static_cast<int>(fminq(33, -log10q(rel))) : 33;
    if (digits < 20) {
      std::fprintf(stderr, "k=%d df=%g q=%.6g: only %d digits, skipped\n", p.k, p.df, p.q, digits);
      continue;
    }
    char q[64];
    std::snprintf(q, sizeof q, "%.6g", p.q);
    std::printf("%d,%s,%s,%s,%s,%d\n", p.k, std::isinf(p.df) ? "Inf" : std::to_string(static_cast<int>(p.df)).c_str(), q,
                Str(ub).c_str(), Str(1 - ub).c_str(), digits);
    std::fflush(stdout);
  }
}
