#pragma once
/// @file Tukey's honestly-significant-difference comparisons, in the three forms analysts
/// meet (every report names the one it uses):
/// - `between`: TukeyHSD on independent groups (Tukey-Kramer for unequal n);
/// - `univariate`: a within-subject factor against the pooled error of its effect
///   (emmeans with `model = "univariate"`);
/// - `multivariate`: a within-subject factor with a per-pair error from the subjects'
///   paired differences, df = n − 1 (emmeans' default for afex objects).
/// Pairs (a, b) run over level pairs i < j with a = level j, b = level i and
/// diff = mean(a) − mean(b), as R's TukeyHSD labels "b-a". (emmeans prints the pair the
/// other way round: its estimate is −diff.)

#include <string>
#include <vector>

#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::stats {

struct TukeyPair {
  std::string a, b;
  double diff = 0, lwr = 0, upr = 0;  ///< diff and its 95 % family-wise interval
  double se = 0;                      ///< standard error of the difference
  double df = 0;
  double q = 0;  ///< studentized range statistic |diff| / (se / sqrt 2)
  double p_adj = 0;
};

struct TukeyResult {
  std::string method;  ///< "between", "univariate" or "multivariate"
  std::string factor;
  int k = 0;
  double mse = 0, df = 0;
  std::vector<TukeyPair> pairs;
};

/// Independent groups of `factor` (every row one observation).
TukeyResult TukeyBetween(const LongTable& data, const std::string& factor, double conf = 0.95);

/// A factor of an rmANOVA or mixed ANOVA result (averaged over the other factors), as emmeans
/// compares it on an afex object: marginal means average the between cells equally.
/// - within factor, univariate: SE^2 = 2 MSE / (cells per level) * (1/G^2) sum_g 1/n_g with
///   the effect's MSE and df (G between cells of n_g subjects; 2 MSE / (n cells) without
///   between factors);
/// - within factor, multivariate: per pair, the subjects' differences d regressed on the
///   between cells: SE^2 = s_d^2 (1/G^2) sum_g 1/n_g, df = N − G (N − 1 without between);
/// - between factor (`method` "between-subjects (mixed ANOVA)"): each subject's mean over all
///   cells, the pooled variance around the between-cell means, df = N − G (the multivariate
///   flag does not matter: both of emmeans' models give this).
/// @param multivariate false: pooled effect error (emmeans univariate); true: per-pair error
TukeyResult TukeyWithin(const RmAnovaResult& anova, const std::string& factor, bool multivariate,
                        double conf = 0.95);

}  // namespace hapticlab::stats
