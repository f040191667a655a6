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
/// +infinity): P(Q <= q). Computed by piecewise Gauss-Legendre quadrature (Boost.Math) of
///   P(Q <= q) = ∫_0^∞ f_ν(s) W(q s) ds,   W(w) = k ∫ φ(z) [Φ(z) − Φ(z − w)]^(k−1) dz,
/// with f_ν the density of sqrt(χ²_ν / ν) [Hartley 1942; Copenhaver & Holland 1988,
/// doi:10.1080/00949658808811068 use Gauss-Legendre instead]. Accurate to ~1e-12 absolute,
/// unlike R's ptukey (up to 3e-4 off at df = 2).
double PtukeyLower(double q, int k, double df);
/// P(Q > q), computed directly (not as 1 − lower), so tiny p-values keep their relative
/// accuracy (~1e-8 down to 1e-300).
double PtukeyUpper(double q, int k, double df);
/// Quantile: the q with P(Q <= q) = p (TOMS 748 root finding, through TukeyFamily).
double Qtukey(double p, int k, double df);

/// The studentized range distribution for one (k, df), for many evaluations: the range
/// distribution W(w) and log(1 − W(w)) are tabulated once as Chebyshev interpolants (160
/// nodes, ~1e-14), so each probability costs one cheap outer integral. Agrees with the
/// direct functions above to ~1e-13 absolute (lower) and ~1e-10 relative (upper).
class TukeyFamily {
 public:
  TukeyFamily(int k, double df);
  double Lower(double q) const;   ///< P(Q <= q)
  double Upper(double q) const;   ///< P(Q > q), relative accuracy kept for tiny p
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
