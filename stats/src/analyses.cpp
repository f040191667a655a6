// The registry of the report's analyses (hapticlab/stats/analysis.hpp) and what every analysis
// shares: the output folder, the criterion's rmANOVA, the study's CSV files.

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/stats/analysis.hpp"

namespace hapticlab::stats {

// Each analysis lives in its own file (stats/src/analysis_*.cpp). One line per analysis here
// (its declaration and its entry), in the order the report runs them.
Analysis AggregateAnalysis();    // analysis_tables.cpp
Analysis RmAnovaAnalysis();      // analysis_anova.cpp
Analysis TukeyAnalysis();        // analysis_anova.cpp
Analysis LmmAnalysis();          // analysis_lmm.cpp
Analysis GroupingAnalysis();     // analysis_grouping.cpp
Analysis KruskalAnalysis();      // analysis_tables.cpp
Analysis ShapiroAnalysis();      // analysis_anova.cpp
Analysis CorrelationAnalysis();  // analysis_tables.cpp

namespace {

std::vector<Analysis>& Registry() {
  static std::vector<Analysis> registry{
      AggregateAnalysis(), RmAnovaAnalysis(), TukeyAnalysis(),   LmmAnalysis(),
      GroupingAnalysis(),  KruskalAnalysis(), ShapiroAnalysis(), CorrelationAnalysis(),
  };
  return registry;
}

}  // namespace

const std::vector<Analysis>& Analyses() { return Registry(); }

const Analysis* FindAnalysis(const std::string& name) {
  for (const auto& a : Registry())
    if (a.name == name) return &a;
  return nullptr;
}

void RegisterAnalysis(Analysis analysis) {
  HL_REQUIRE(!analysis.name.empty() && analysis.run, "an analysis needs a keyword and a run");
  HL_REQUIRE(FindAnalysis(analysis.name) == nullptr,
             "analysis '" + analysis.name + "' is registered already");
  Registry().push_back(std::move(analysis));
}

std::string AnalysisNames() {
  std::string out;
  for (const auto& a : Registry()) out += (out.empty() ? "" : ", ") + a.name;
  return out;
}

void CheckAnalyses(const protocols::Protocol& protocol) {
  for (const auto& a : protocol.analyses)
    if (!FindAnalysis(a))
      throw InputError(protocol.file, protocol.analyses_line, "analysis.tests",
                       "unknown analysis '" + a + "' (expected " + AnalysisNames() + ")");
}

void NotRun(std::ostream& md, const std::string& analysis, const std::string& why) {
  md << "\n*`" << analysis << "` was requested but not run: " << why << "*\n";
}

std::ofstream ReportWriter::Open(const std::string& name) {
  const std::string path = Path(name);
  files_.push_back(path);
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write");
  return f;
}

std::string ReportWriter::Path(const std::string& name) const {
  return (std::filesystem::path(dir_) / name).string();
}

const RmAnovaResult* AnalysisContext::Anova(std::string* why) {
  if (!anova_tried_) {
    anova_tried_ = true;
    std::vector<std::string> within;
    if (methods.size() >= 2) within.push_back("method");
    if (materials.size() >= 2) within.push_back("material");
    const std::size_t n_participants = ratings.Levels("participant").size();
    if (within.empty())
      anova_why_ =
          "it needs a within factor with two or more levels (this study has one method and one "
          "material)";
    else if (n_participants < 2)
      anova_why_ = fmt::format("it needs two or more participants ({} so far)", n_participants);
    else
      try {
        anova_ = RmAnova(ratings, "participant", within);
      } catch (const InputError& e) {
        anova_why_ = e.what();
      }
  }
  if (why) *why = anova_why_;
  return anova_ ? &*anova_ : nullptr;
}

std::ofstream& AnalysisContext::StudyCsv(const std::string& name, const std::string& header) {
  HL_REQUIRE(study_state != nullptr, "a study CSV needs the study's state");
  auto it = study_state->csv.find(name);
  if (it == study_state->csv.end()) {
    it = study_state->csv.emplace(name, writer.Open(name)).first;
    it->second << header;
  }
  return it->second;
}

}  // namespace hapticlab::stats
