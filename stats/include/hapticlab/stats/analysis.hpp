#pragma once
/// @file The statistical analyses a protocol may name in `[analysis] tests`, registered by
/// keyword. Each analysis is a function that writes its own section of the report (Markdown,
/// CSV tables, figures) from an AnalysisContext; `hapticlab analyze` runs, for every study
/// and criterion, the protocol's analyses in the registry's order.
///
/// Adding an analysis: write `stats/src/analysis_<name>.cpp` with a function returning its
/// `Analysis` (keyword, scope, run), and add that function to the list in
/// stats/src/analyses.cpp (its declaration and its entry). The protocol's allowed keywords
/// are the registry's names (CheckAnalyses); docs/architecture.md "Adding an analysis".

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/long_table.hpp"
#include "hapticlab/stats/plot.hpp"

namespace hapticlab::protocols {
struct Protocol;
}

namespace hapticlab::stats {

/// The report's output folder: every file an analysis writes is opened (or added) here, so
/// the report lists it.
class ReportWriter {
 public:
  explicit ReportWriter(std::string dir) : dir_(std::move(dir)) {}
  /// Opens `<dir>/<name>` for writing. @throws std::runtime_error when it cannot.
  std::ofstream Open(const std::string& name);
  /// Records files written by others (figures).
  void Add(const std::vector<std::string>& files) {
    files_.insert(files_.end(), files.begin(), files.end());
  }
  /// `<dir>/<name>` without opening it (a figure's base name).
  std::string Path(const std::string& name) const;
  const std::string& dir() const { return dir_; }
  const std::vector<std::string>& files() const { return files_; }

 private:
  std::string dir_;
  std::vector<std::string> files_;
};

/// What an analysis sees. Per-criterion analyses get one criterion's main-phase ratings;
/// study analyses get the whole main phase (criterion empty).
struct AnalysisContext {
  AnalysisContext(const protocols::Protocol& protocol, const LongTable& main_ratings,
                  std::ostream& markdown, ReportWriter& out)
      : proto(protocol), ratings(main_ratings), md(markdown), writer(out) {}

  const protocols::Protocol& proto;
  std::string study;      ///< the study's name
  std::string criterion;  ///< "" for a study analysis
  /// File name prefix: "<study>_<criterion>" (or "<study>"), safe in a file name.
  std::string file_prefix;
  const LongTable& ratings;  ///< main-phase ratings (of the criterion, for a criterion analysis)
  std::vector<std::string> methods, materials;  ///< present, in the protocol's order
  /// Real-real limits from the reference phase (same material / different materials); empty
  /// tables and NaN means without a reference phase.
  LongTable same, different;
  double upper = NAN, lower = NAN;
  Correction correction = Correction::kGG;
  bool figures = true;
  std::ostream& md;      ///< the report's Markdown
  ReportWriter& writer;  ///< the output folder
  /// The per-material bar chart of the criterion (Figs. 4.8, 5.8), drawn after every analysis
  /// of the criterion ran: an analysis may add to it (the grouping letters and limits).
  BarChart* material_chart = nullptr;
  /// The names of the protocol's analyses (an analysis may defer to another one).
  std::vector<std::string> requested;

  /// The repeated-measures ANOVA (participant; method and material where they have two or
  /// more levels), computed once per criterion for every analysis that needs it; nullopt with
  /// `why` when it cannot be computed.
  const RmAnovaResult* Anova(std::string* why);
  /// A CSV shared by the criteria of a study (opened with `header` on first use).
  std::ofstream& StudyCsv(const std::string& name, const std::string& header);

  /// Shared state of one study, kept by the report between its criteria.
  struct StudyState {
    std::map<std::string, std::ofstream> csv;
  };
  StudyState* study_state = nullptr;

 private:
  bool anova_tried_ = false;
  std::optional<RmAnovaResult> anova_;
  std::string anova_why_;
};

struct Analysis {
  std::string name;     ///< the keyword in `[analysis] tests`
  std::string summary;  ///< one line, for messages and docs
  enum class Scope { kCriterion, kStudy };
  Scope scope = Scope::kCriterion;
  /// Writes the analysis's section (or says in it why it could not run).
  std::function<void(AnalysisContext&)> run;
};

/// The registered analyses, in the order the report runs them.
const std::vector<Analysis>& Analyses();
/// The analysis of a keyword; nullptr when none is registered.
const Analysis* FindAnalysis(const std::string& name);
/// Adds an analysis after the others (an extension, a test's toy analysis).
/// @throws PreconditionError when the keyword is taken or the analysis has no run function
void RegisterAnalysis(Analysis analysis);
/// "rm-anova, tukey, ..." (the keywords, in order).
std::string AnalysisNames();
/// Every keyword of the protocol's `[analysis] tests` is registered.
/// @throws InputError naming the protocol file, the line of `tests` and the keyword
void CheckAnalyses(const protocols::Protocol& protocol);

/// A requested analysis that cannot run says why, in the report (never dropped silently).
void NotRun(std::ostream& md, const std::string& analysis, const std::string& why);

}  // namespace hapticlab::stats
