#pragma once
/// @file The adaptive-phase section of `hapticlab analyze` (docs/psychophysics.md): per
/// participant and pooled, the ML psychometric fit of every answer of a staircase or QUEST+
/// phase with parametric-bootstrap intervals, the JND (the stimulus difference at the phase's
/// jnd_performance) and the Weber fraction (JND / reference), plus a figure of the fitted
/// curve over the binned data.

#include <cstdint>
#include <string>
#include <vector>

#include "hapticlab/stats/psychometric.hpp"

namespace hapticlab::stats {

/// One answered adaptive trial as the record holds it.
struct AdaptiveAnswer {
  std::string participant;
  double level = 0;       ///< x = comparison - reference, in the parameter's unit
  bool positive = false;  ///< correct (m-AFC) or yes
  int track = 0;
};

/// Every answered trial of adaptive phase `phase_index` of study `study` in the database.
std::vector<AdaptiveAnswer> AdaptiveAnswers(const std::string& db_path, const std::string& study,
                                            int phase_index);

/// Bins answers for plotting: exact levels pooled; more than `max_bins` levels are grouped
/// into `max_bins` bins of about equal trial counts, each at its trials' mean level.
PsychometricData BinForPlot(const PsychometricData& pooled, int max_bins = 10);

struct PsychometricPlot {
  std::string title, x_label;
  PsychometricData binned;  ///< points, area proportional to the trial count
  psychophysics::Shape shape = psychophysics::Shape::kWeibull;
  psychophysics::PsychometricParams fit;  ///< the curve
  double jnd = 0;                         ///< marked with a vertical line when finite
  double jnd_performance = 0.75;
};
/// `<base>.svg` and `<base>.png`.
std::vector<std::string> DrawPsychometricPlot(const PsychometricPlot& plot,
                                              const std::string& base);

/// Markdown for the adaptive phases of one study (empty when it has none); writes
/// `<study>_psychometric.csv` and one figure per phase into `out_dir`, appending their paths to
/// `files`. `bootstrap_replicates` per fit; seed fixed, so the report is reproducible.
std::string AdaptiveReport(const std::string& db_path, const std::string& study,
                           const std::string& protocol_toml, const std::string& out_dir,
                           bool figures, std::vector<std::string>* files,
                           int bootstrap_replicates = 1000);

}  // namespace hapticlab::stats
