#include "hapticlab/stats/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <ostream>
#include <set>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/latency_histogram.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/db/timing.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/stats/analysis.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/descriptive.hpp"
#include "hapticlab/stats/distributions.hpp"
#include "hapticlab/stats/lmm.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "hapticlab/stats/plot.hpp"
#include "hapticlab/stats/psychometric_report.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/stats/tukey.hpp"
#include "hapticlab/stats/within_ci.hpp"
#include "report_internal.hpp"

namespace hapticlab::stats {

using namespace report_internal;

namespace {

// The report's opening: what the numbers are and how they were computed.
constexpr const char* kPreamble =
    "Scores are similarity ratings on the protocol's scale. Repetitions are averaged per "
    "participant x cell before repeated-measures ANOVA (as afex does). Tukey comparisons of a "
    "within-subject factor use the pooled error of its effect (emmeans `model = "
    "\"univariate\"`). Error bars beside these within-subject tests are 95 % within-subject "
    "confidence intervals (Cousineau 2005 with Morey's 2008 correction, as afex_plot and "
    "Rmisc::summarySEwithin). Outliers (1.5 IQR, Tukey's hinges) are counted, not removed.\n";

// Where the ratings came from: a person's input device or the simulated observer.
void SourcesSentence(std::ostream& md, const RatingSources& sources, const std::string& study) {
  const auto count = [&](const std::map<std::string, std::size_t>& m) {
    const auto it = m.find(study);
    return it == m.end() ? std::size_t{0} : it->second;
  };
  const std::size_t human = count(sources.human), kept = count(sources.simulated_kept),
                    excluded = count(sources.simulated_excluded);
  if (excluded)
    md << "\n**Simulated ratings excluded:** " << excluded
       << " ratings of the simulated observer (sessions or parts of sessions run without a "
          "person rating) are left out of this study's "
       << human
       << " ratings by participants; `hapticlab analyze --include-simulated` keeps them.\n";
  else if (kept && human)
    md << "\n**Simulated ratings included** (`--include-simulated`): " << kept
       << " ratings of the simulated observer are analysed together with " << human
       << " ratings by participants.\n";
  else if (kept)
    md << "\nAll ratings come from the simulated observer (a simulated study).\n";
}

// Splits the reference phase's ratings of a criterion into same-material and
// different-material pairs, their means being the real-real limits.
void RealRealLimits(const LongTable& ref, AnalysisContext& c) {
  if (!ref.rows()) return;
  const auto rc = ref.Where({{"criterion", c.criterion}});
  c.same = rc;
  c.same.keys.assign(rc.key_names.size(), {});
  c.same.y.clear();
  c.different = c.same;
  for (std::size_t i = 0; i < rc.rows(); ++i) {
    auto& dst =
        rc.keys[rc.Key("material")][i] == rc.keys[rc.Key("comparison")][i] ? c.same : c.different;
    for (std::size_t k = 0; k < rc.key_names.size(); ++k) dst.keys[k].push_back(rc.keys[k][i]);
    dst.y.push_back(rc.y[i]);
  }
  if (c.same.rows()) c.upper = Describe(c.same.y).mean;
  if (c.different.rows()) c.lower = Describe(c.different.y).mean;
  c.md << fmt::format(
      "\nReal-real limits: upper {:.2f} (same material, n = {}), lower {:.2f} (different "
      "materials, n = {}).\n",
      c.upper, c.same.rows(), c.lower, c.different.rows());
}

// The criterion's figures drawn after its analyses: the per-material bars (Figs. 4.8, 5.8,
// with what the analyses added) and the box plot of the raw ratings by method.
void CriterionFigures(AnalysisContext& c, const BarChart& bm) {
  const auto base = c.writer.Path(c.file_prefix + "_materials");
  c.writer.Add(DrawBarChart(bm, base));
  c.md << "\n![" << c.criterion << " by material](" << fs::path(base).filename().string()
       << ".png)\n\n(Error bars: " << bm.error_label << ".)\n";
  BoxPlot bp;
  bp.title = fmt::format("{}: {} ratings", c.proto.title, c.criterion);
  bp.x_label = "rendering method";
  bp.y_label = c.criterion + " similarity";
  for (const auto& me : c.methods) {
    bp.groups.push_back(me);
    bp.samples.push_back(c.ratings.Where({{"method", me}}).y);
  }
  const auto bbase = c.writer.Path(c.file_prefix + "_box");
  c.writer.Add(DrawBoxPlot(bp, bbase));
  c.md << "\n![" << c.criterion << " box plot](" << fs::path(bbase).filename().string()
       << ".png)\n";
}

// What every analysis of a study shares.
struct StudyInputs {
  const protocols::Protocol& proto;
  std::string name;
  Correction correction;
  bool figures;
  LongTable main, ref;
  std::vector<std::string> methods, materials;
};

AnalysisContext Context(const StudyInputs& s, const LongTable& ratings, std::ostream& md,
                        ReportWriter& w, AnalysisContext::StudyState& state) {
  AnalysisContext c(s.proto, ratings, md, w);
  c.study = s.name;
  c.file_prefix = Safe(s.name);
  c.methods = s.methods;
  c.materials = s.materials;
  c.correction = s.correction;
  c.figures = s.figures;
  c.requested = s.proto.analyses;
  c.study_state = &state;
  return c;
}

// A registered analysis the protocol asks for, in the registry's order; an unknown keyword
// (a database from another version) is said, not dropped.
bool Requested(const protocols::Protocol& proto, const Analysis& a) {
  return std::count(proto.analyses.begin(), proto.analyses.end(), a.name) > 0;
}

void CriterionSection(const StudyInputs& s, const std::string& crit, std::ostream& md,
                      ReportWriter& w, AnalysisContext::StudyState& state) {
  const auto cm = s.main.Where({{"criterion", crit}});
  md << "\n### " << crit << "\n";
  AnalysisContext c = Context(s, cm, md, w, state);
  c.criterion = crit;
  c.file_prefix += "_" + Safe(crit);
  RealRealLimits(s.ref, c);
  if (cm.rows() == 0) {
    md << "\nNo main-phase ratings of " << crit << " yet: the protocol's analyses need them.\n";
    return;
  }
  BarChart bm;
  bm.title = fmt::format("{}: {} similarity by material", s.proto.title, crit);
  bm.x_label = "material";
  bm.y_label = crit + " similarity";
  bm.groups = s.materials;
  MaterialSeries(bm, cm, s.methods, s.materials);
  c.material_chart = &bm;
  for (const auto& a : Analyses())
    if (a.scope == Analysis::Scope::kCriterion && Requested(s.proto, a)) a.run(c);
  if (s.figures) CriterionFigures(c, bm);
}

void StudySection(const db::Database& d, const std::string& db_path, const db::Study& st,
                  const LongTable& study, const RatingSources& sources, const ReportOptions& o,
                  std::ostream& md, ReportWriter& w) {
  const auto proto = protocols::ParseProtocol(st.protocol_toml, "(protocol of " + st.name + ")");
  StudyInputs s{proto,
                st.name,
                o.correction.empty()
                    ? ParseCorrection(proto.correction, st.name, "analysis.correction")
                    : ParseCorrection(o.correction, "<command line>", "--correction"),
                o.figures,
                study.Where({{"phase", "main"}}),
                study.Where({{"phase", "reference"}}),
                {},
                {}};
  md << "\n## Study `" << st.name << "`\n\n"
     << proto.description << "\n\n"
     << "Participants: " << study.Levels("participant").size() << "; ratings: " << study.rows()
     << "\n"
     << fmt::format(
            "\nRating scale: {:g} to {:g} (the protocol's `scale`); means, differences and "
            "their confidence intervals below are in points of this scale.\n",
            proto.scale_min, proto.scale_max);
  for (const auto& a : proto.analyses)
    if (!FindAnalysis(a))
      NotRun(md, a, "no analysis of that name is registered (expected " + AnalysisNames() + ")");
  SourcesSentence(md, sources, st.name);
  md << "\n" << TimingMethodsSentence(d, st.id);
  if (o.study_section) md << o.study_section(d, st);  // analyze --plan: deviations
  // Adaptive phases (staircase, QUEST+): psychometric fits, JND and Weber fraction.
  std::vector<std::string> adaptive_files;
  md << AdaptiveReport(db_path, st.name, st.protocol_toml, o.out_dir, o.figures, &adaptive_files);
  w.Add(adaptive_files);
  md << MultiSiteSection(d, st.id, proto, study, w, o.figures);  // docs/replication.md
  if (s.main.rows() + s.ref.rows() == 0) return;
  std::vector<std::string> proto_methods, proto_materials;
  for (const auto& m : proto.methods) proto_methods.push_back(m.name);
  for (const auto& m : proto.materials) proto_materials.push_back(m.id);
  if (s.main.rows()) {
    s.methods = InProtocolOrder(proto_methods, s.main.Levels("method"));
    s.materials = InProtocolOrder(proto_materials, s.main.Levels("material"));
  }
  AnalysisContext::StudyState state;
  for (const auto& crit : proto.criteria) CriterionSection(s, crit, md, w, state);
  AnalysisContext c = Context(s, s.main, md, w, state);
  for (const auto& a : Analyses())
    if (a.scope == Analysis::Scope::kStudy && Requested(proto, a)) a.run(c);
}

}  // namespace

ReportResult Analyze(const std::string& db_path, const ReportOptions& o) {
  RatingSources sources;
  const LongTable all = RatingsFromDatabase(db_path, o.include_simulated, &sources);
  if (all.rows() == 0) throw InputError(db_path, 0, "", "the database holds no ratings yet");
  fs::create_directories(o.out_dir);
  Writer w(o.out_dir);
  ReportResult res;
  db::Database d(db_path, {.create = false, .read_only = true});
  auto md = w.Open("report.md");
  // The database by its file name: a folder would carry a user or host name into the report.
  md << "# HapticLab analysis report\n\nDatabase: `" << fs::path(db_path).filename().string()
     << "`\n\n"
     << kPreamble;
  for (const auto& st : d.Studies()) {
    const auto study = all.Where({{"study", st.name}});
    if (study.rows() == 0) continue;
    res.studies.push_back(st.name);
    StudySection(d, db_path, st, study, sources, o, md, w);
  }
  md.close();
  res.markdown = (fs::path(o.out_dir) / "report.md").string();
  res.files = w.files();
  return res;
}

}  // namespace hapticlab::stats
