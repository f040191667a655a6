#pragma once
/// @file Repeated-measures and mixed ANOVA (within-subject factors, optionally crossed with
/// between-subject factors), as afex::aov_ez computes it (type 3 sums of squares):
/// repetitions are averaged per subject x cell, a subject with a missing cell is dropped
/// (and named), each within effect is tested against its own effect x subject error term.
///
/// With between factors, the subjects' cell means Y (subjects x cells) are regressed on the
/// between design X (intercept and sum-to-zero coded main effects and interactions of the
/// between factors, full factorial, as car::Anova with contr.sum). For a within term with
/// orthonormal contrasts P (the intercept term: P = 1/sqrt(cells)) and a between term T with
/// coefficient rows L: Z = Y P, B = (X'X)^-1 X'Z, E = Z - X B,
/// SS = tr[(L B)' (L (X'X)^-1 L')^-1 (L B)], SS_error = tr(E'E), df1 = cols(P) rows(L),
/// df2 = cols(P) (N - rank X). Sphericity statistics use S = E'E / (N - rank X) with error
/// df N - rank X (car: Huynh-Feldt ((ν + 1) p ε_GG − 2) / (p (ν − p ε_GG))). Without between
/// factors this is the plain repeated-measures ANOVA below (X = 1, ν = N − 1).
///
/// For an effect with orthonormal contrast matrix P (cells x df1), Z = Y P (subjects x
/// df1): SS = n |mean(Z)|^2, SS_error = trace of the centred Z'Z, S = cov(Z). Sphericity:
/// Mauchly's W = det S / (tr S / p)^p with R's p-value (mauchly.test: second-order
/// correction) and the first-order chi-square (SPSS) beside it; Greenhouse-Geisser
/// ε = tr(S)^2 / (p tr(S^2)); Huynh-Feldt (Lecoutre) ε = (N p ε_GG − 2) / (p (N − 1 − p ε_GG))
/// reported uncapped (as R), its p-value using min(1, ε) (floored at 1/df1, where tiny
/// samples push the formula below it and R returns NaN). Where p > N − 1 the covariance is
/// singular: Mauchly's test does not exist (its fields are NaN and `mauchly_defined` is
/// false, as car/afex report nothing), but ε is still defined and we report it (as SPSS and
/// the direct computation in tools/stats_oracle.R's gg_manual do; afex prints uncorrected
/// df there). For p = 1 sphericity holds trivially (W = 1, ε = 1).

#include <string>
#include <vector>

#include "hapticlab/stats/long_table.hpp"

namespace hapticlab::stats {

struct AnovaEffect {
  std::string effect;  ///< "A", "B", "A:B"
  bool between_only =
      false;  ///< a between-subjects term (no sphericity statistics: ε = 1, Mauchly NaN)
  double df1 = 0, df2 = 0;
  double SS = 0, SS_error = 0, MSE = 0;
  double F = 0, p = 0;
  double pes = 0;  ///< partial eta squared SS / (SS + SS_error)
  bool mauchly_defined = false;
  double mauchly_W = 0, mauchly_p = 0, mauchly_chi2 = 0, mauchly_p_firstorder = 0;
  double gg_epsilon = 0, p_gg = 0;
  double hf_epsilon = 0, p_hf = 0;  ///< hf_epsilon uncapped; p_hf uses min(1, ε)
  double hf_epsilon_used = 1;       ///< the ε p_hf uses: min(1, ε) floored at 1/df
};

struct RmAnovaResult {
  std::vector<std::string> factors;              ///< within factors
  std::vector<std::vector<std::string>> levels;  ///< sorted levels of each within factor
  std::vector<std::string> between;  ///< between factors (empty: repeated measures only)
  std::vector<std::vector<std::string>> between_levels;  ///< sorted levels of each between factor
  std::vector<std::string> subjects;                     ///< kept subjects, sorted
  /// Between cell of each kept subject (index over the between factors' level combinations,
  /// last factor fastest); all 0 without between factors.
  std::vector<int> subject_group;
  std::vector<int> group_sizes;               ///< kept subjects per between cell
  std::vector<std::string> dropped_subjects;  ///< subjects with a missing cell
  /// Why each dropped subject went, parallel to dropped_subjects: the missing cells, e.g.
  /// "no rating for method=visual" (or the file line of a missing score).
  std::vector<std::string> dropped_reasons;
  double error_df = 0;  ///< N − rank X (N − 1 without between factors)
  /// Effects in afex's order: between terms, then each within term followed by its
  /// interactions with the between terms ("group:method").
  std::vector<AnovaEffect> effects;
  /// Cell means: cells[s][c], cell index c with the last factor fastest.
  std::vector<std::vector<double>> cells;
};

/// @param data long table with the subject column and the factor columns as keys; a NaN
///        response (a missing score read with ReadLongCsv's allow_missing) leaves its cell
///        unobserved, so its subject is dropped (and named) as afex does
/// @param between between-subject factors (each subject must have exactly one level)
/// @throws hapticlab::InputError when fewer than 2 subjects remain, a factor has 1 level, a
///         within factor is constant within every subject (it is between-subjects: the
///         message says to give it with --between), a between factor varies within a
///         subject, or a between cell has no subject left
RmAnovaResult RmAnova(const LongTable& data, const std::string& subject,
                      const std::vector<std::string>& within,
                      const std::vector<std::string>& between = {});

/// The sphericity correction of within-subject effects, by afex's names (the `correction`
/// argument of afex::anova_table): "GG" Greenhouse-Geisser (afex's default), "HF" Huynh-Feldt,
/// "none". As afex, a correction applies to every within effect, whatever Mauchly's test says;
/// unlike afex (car), which prints uncorrected df where the covariance is singular (no
/// Mauchly test), the ε computed from that covariance is applied there too, so a p that
/// assumes an untestable sphericity is never the one a conclusion rests on.
enum class Correction { kGG, kHF, kNone };
/// "GG", "HF" or "none". @throws InputError naming `source` and `field` otherwise.
Correction ParseCorrection(const std::string& name, const std::string& source,
                           const std::string& field);
const char* CorrectionName(Correction c);
/// The ε `c` applies to `e` (1 for between-only effects and for kNone).
double UsedEpsilon(const AnovaEffect& e, Correction c);
/// The p that decides whether `e` is significant under `c` (p, p_gg or p_hf).
double UsedP(const AnovaEffect& e, Correction c);

/// Residuals of the fit, as afex's residuals() of an aov_ez fit (the residuals of its
/// multivariate lm): each kept subject's cell mean minus the mean of that cell over the
/// subjects of its between group. Subject-major (a.subjects' order), cells as in a.cells.
std::vector<double> AnovaResiduals(const RmAnovaResult& a);

/// One-way between-subjects ANOVA (every row an independent observation). Sums of squares
/// are formed from centred values (two passes), which keeps NIST StRD's hard cases
/// (SiRstv, values near 196 with SS_between 0.05) accurate.
struct OneWayResult {
  double df_between = 0, df_within = 0;
  double SS_between = 0, SS_within = 0, MS_between = 0, MS_within = 0;
  double F = 0, p = 0;
  double r_squared = 0, residual_sd = 0;
};
OneWayResult OneWayAnova(const LongTable& data, const std::string& factor);

/// Sphericity statistics of a one-way within factor from the k x k covariance of its levels
/// (n − 1 denominator): S is projected on orthonormal contrasts C (k x (k−1)), C'SC, then
/// treated as above; exposed for tests against published values.
struct Sphericity {
  bool mauchly_defined = false;  ///< false when S is singular (p > n − 1); ε is always set
  double W = 0, chi2 = 0, p_firstorder = 0, p = 0, gg = 0, hf = 0;
};
/// @param S k x k covariance of the levels
/// @param n number of subjects
Sphericity SphericityFromLevelCovariance(const std::vector<std::vector<double>>& S, int n);

}  // namespace hapticlab::stats
