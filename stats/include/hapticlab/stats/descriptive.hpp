#pragma once
/// @file Descriptive statistics, the boxplot outlier rule, and correlations.

#include <string>
#include <vector>

namespace hapticlab::stats {

struct Descriptives {
  int n = 0;
  double mean = 0, sd = 0, se = 0, median = 0;
  double ci95_lo = 0, ci95_hi = 0;  ///< mean ± t(0.975, n − 1) se
};
Descriptives Describe(const std::vector<double>& x);

/// Quartile definition of the 1.5 IQR rule.
enum class QuartileRule {
  kHinges,  ///< Tukey's hinges, R's boxplot()/fivenum() (what the dissertation's box plots show)
  kType7,   ///< R's quantile() default, rstatix::identify_outliers
};
struct OutlierFence {
  double q1 = 0, q3 = 0, lower = 0, upper = 0;
  std::vector<std::size_t> outliers;  ///< indices into the input outside [lower, upper]
};
OutlierFence Outliers(const std::vector<double>& x, QuartileRule rule, double coef = 1.5);

struct Correlation {
  int n = 0;
  double r = 0;  ///< estimate
  double t = 0;  ///< r sqrt((n − 2)/(1 − r^2))
  double p = 0;  ///< two-sided, t(n − 2)
};
Correlation Pearson(const std::vector<double>& x, const std::vector<double>& y);
/// Spearman's rho with the t approximation (R's cor.test(method = "spearman", exact = FALSE)).
Correlation Spearman(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace hapticlab::stats
