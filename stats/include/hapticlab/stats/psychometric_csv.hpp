#pragma once
/// @file Psychometric fits of binomial data in a CSV (`hapticlab stats psychometric`): the
/// links the command names, the reader of (level, correct, trials) rows, and one summary
/// per group (fit, parametric bootstrap, stimuli at chosen performances, JND, Weber
/// fraction) computed by the same fit and bootstrap as the adaptive phases of `analyze`
/// (stats/psychometric.hpp; docs/psychophysics.md).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hapticlab/stats/psychometric.hpp"

namespace hapticlab::stats {

/// A link of `--link`: the shape of F and the guess rate it fixes.
/// "logit", "probit", "weibull" (guess 0: R's binomial logit, probit, cloglog of ln x) and
/// "mafc-logit:m", "mafc-probit:m", "mafc-weibull:m" (guess 1/m, m >= 2: psyphy's
/// mafc.logit(m), mafc.probit(m), mafc.cloglog(m)).
struct PsychometricLink {
  std::string name;
  psychophysics::Shape shape = psychophysics::Shape::kLogistic;
  double guess = 0;  ///< dimensionless
};
/// The link named by `text`; nullopt with `why` set when it names none.
std::optional<PsychometricLink> ParsePsychometricLink(const std::string& text, std::string* why);

/// Which columns hold the data: the stimulus level, the positive (correct) count, and either
/// the number of trials or the negative (incorrect) count (exactly one of the two);
/// optionally the columns whose combinations split the rows into groups fitted separately.
struct PsychometricColumns {
  std::string level, correct, trials, incorrect;
  std::vector<std::string> by;
};

/// The rows of one group (one combination of the `by` columns' values).
struct PsychometricGroup {
  std::vector<std::pair<std::string, std::string>> keys;  ///< (column, value); empty: all rows
  PsychometricData data;                                  ///< in file order, not pooled
  std::string Name() const;                               ///< "task=DET, Size=12.4", or "all"
};

/// Reads the CSV into groups in the order their first rows appear. Every kept cell is checked:
/// the level must be a finite number (> 0 when `positive_levels`, for a Weibull), counts whole
/// numbers >= 0 with correct <= trials and trials >= 1.
/// @throws InputError naming the file, the line and the column, and what was expected.
std::vector<PsychometricGroup> ReadPsychometricCsv(const std::string& path,
                                                   const PsychometricColumns& columns,
                                                   bool positive_levels);

struct PsychometricSummaryOptions {
  PsychometricFitOptions fit;
  std::vector<double> performances;  ///< report the stimulus at each (in (guess, 1))
  double jnd_performance = 0.75;     ///< JND = the stimulus at this performance
  double reference = 0;              ///< > 0: Weber fraction = JND / reference
  int replicates = 1000;             ///< parametric bootstrap refits; 0: no intervals
  std::uint64_t seed = 1;
  double level = 0.95;  ///< of the percentile intervals
};

/// One fit with its intervals. Stimuli a fit cannot reach (performance above 1 - lapse) are
/// NaN; intervals are NaN without a bootstrap.
struct PsychometricSummary {
  int trials = 0;
  PsychometricFit fit;
  PsychometricBootstrap boot;
  std::vector<double> stimulus_at;  ///< per options.performances
  double jnd = 0, weber = 0;        ///< weber NaN without a reference
  BootstrapInterval weber_ci;
};

/// Fits `data`, then (when usable and replicates >= 2) bootstraps it. The adaptive phases of
/// `analyze` call this too. @throws PreconditionError for invalid options.
PsychometricSummary SummarizePsychometric(const PsychometricData& data,
                                          const PsychometricSummaryOptions& options);

}  // namespace hapticlab::stats
