#pragma once
/// @file Distribution functions for the tests. F, chi-square, t and normal come from
/// Boost.Math; the studentized range distribution (ptukey/qtukey) is written here because no
/// maintained C++ library offers it.

#include <memory>

namespace hapticlab::stats {

/// P(F > f) for F(df1, df2); non-integer df allowed (Greenhouse-Geisser corrections).
double PfUpper(double f, double df1, double df2);
/// Quantile of F(df1, df2).
double Qf(double p, double df1, double df2);
/// P(X > x) for chi-square(df).
double PchisqUpper(double x, double df);
/// P(|T| > |t|) for Student's t(df).
double PtTwoSided(double t, double df);
/// Quantile of Student's t(df).
double Qt(double p, double df);
/// P(|Z| > |z|) for the standard normal.
double PnormTwoSided(double z);
/// Standard normal upper tail P(Z > z), accurate far into the tail.
double PnormUpper(double z);

/// Studentized range distribution of k means with df error degrees of freedom (df may be
/// +infinity): P(Q <= q). Computed by Gauss-Legendre quadrature (Boost.Math) of
///   P(Q <= q) = ∫_0^∞ f_ν(s) W(q s) ds,   W(w) = k ∫ φ(z) [Φ(z) − Φ(z − w)]^(k−1) dz,
/// with f_ν the density of sqrt(χ²_ν / ν) [Hartley 1942; Copenhaver & Holland 1988,
/// doi:10.1080/00949658808811068 use Gauss-Legendre too]. The outer integrand has two
/// scales (the chi density's, ~1/sqrt(2ν), and the range distribution's, ~1/q); its
/// panels are centred on its peak and sized by its curvature there, so large q with small
/// ν (k = 10, ν = 7, q = 27.7407, tests/stats/distributions_test.cpp) keeps full accuracy. The
/// smaller of the two tails is integrated directly and the other is its complement. Checked against
/// extended- and 113-bit-precision quadrature (tests/data/stats/tukey_reference.csv): 1e-8
/// relative or better on both tails over k = 2..20, ν = 2..1000 and ∞, upper tails down to
/// 1e-15 (R's ptukey is off by up to 3e-4 at ν = 2 and floors near 1e-12 in upper tails).
double PtukeyLower(double q, int k, double df);
/// P(Q > q), computed directly (not as 1 − lower), so tiny p-values keep their relative
/// accuracy (tested to 1e-8 relative down to 1e-15; a few ms per call).
double PtukeyUpper(double q, int k, double df);
/// Quantile: the q with P(Q <= q) = p (TOMS 748 root finding, through TukeyFamily).
double Qtukey(double p, int k, double df);

/// The studentized range distribution for one (k, df), for many evaluations: the range
/// distribution W(w) and log(1 − W(w)) are tabulated once as Chebyshev interpolants (160
/// nodes, ~1e-14), so each probability costs one cheap outer integral. Tested to the same
/// 1e-8 relative as the direct functions (tests/stats/tukey_accuracy_test.cpp).
class TukeyFamily {
 public:
  TukeyFamily(int k, double df);
  double Lower(double q) const;  ///< P(Q <= q)
  double Upper(double q) const;  ///< P(Q > q), relative accuracy kept for tiny p
  double Quantile(double p) const;
  int k() const { return k_; }
  double df() const { return df_; }

 private:
  struct Tables;
  int k_;
  double df_;
  std::shared_ptr<const Tables> tables_;
};

}  // namespace hapticlab::stats
