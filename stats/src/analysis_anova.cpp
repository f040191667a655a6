// The analyses on the criterion's repeated-measures ANOVA: `rm-anova` (Tables 5.2, 5.3),
// `tukey` (method pairs with the bar chart of Figs. 5.7/5.8) and `shapiro` (normality of the
// ANOVA's residuals, with outlier counts).

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "hapticlab/stats/analysis.hpp"
#include "hapticlab/stats/descriptive.hpp"
#include "hapticlab/stats/tukey.hpp"
#include "hapticlab/stats/within_ci.hpp"
#include "report_internal.hpp"

namespace hapticlab::stats {

using namespace report_internal;

namespace {

void RunRmAnova(AnalysisContext& c) {
  std::string why;
  const RmAnovaResult* anova = c.Anova(&why);
  if (!anova) return NotRun(c.md, "rm-anova", why);
  auto csv = c.writer.Open(c.file_prefix + "_rmanova.csv");
  csv << "effect,df1,df2,F,p,pes,mauchly_W,mauchly_p,gg_epsilon,p_gg,hf_epsilon,p_hf,"
         "correction,p_used\n";
  AnovaTable(c.md, csv, *anova, c.correction);
}

// The method bar chart of Figs. 5.7/5.8: within-subject CIs and the Tukey stars.
BarChart MethodChart(const AnalysisContext& c, const TukeyResult& tk) {
  BarChart bc;
  bc.title = fmt::format("{}: {} similarity", c.proto.title, c.criterion);
  bc.x_label = "rendering method";
  bc.y_label = c.criterion + " similarity";
  bc.error_label = kWithinCiLabel;
  bc.groups = {""};
  const auto ci = WithinSubjectCi(c.ratings, "participant", {"method"});
  for (const auto& me : c.methods)
    for (const auto& cell : ci)
      if (cell.cell[0] == me) bc.series.push_back({me, {cell.mean}, {cell.half_width}});
  for (const auto& pr : tk.pairs)
    if (pr.p_adj < 0.05) {
      const auto ia = std::find(c.methods.begin(), c.methods.end(), pr.a) - c.methods.begin();
      const auto ib = std::find(c.methods.begin(), c.methods.end(), pr.b) - c.methods.begin();
      bc.marks.push_back({static_cast<int>(std::min(ia, ib)), static_cast<int>(std::max(ia, ib)),
                          Stars(pr.p_adj)});
    }
  return bc;
}

void RunTukey(AnalysisContext& c) {
  std::string why;
  const RmAnovaResult* anova = c.methods.size() < 2 ? nullptr : c.Anova(&why);
  if (c.methods.size() < 2)
    return NotRun(
        c.md, "tukey",
        fmt::format("it compares methods and this study has {} method", c.methods.size()));
  if (!anova)
    return NotRun(c.md, "tukey",
                  "it uses the repeated-measures ANOVA's error term, which could not be "
                  "computed: " +
                      why);
  const auto tk = TukeyWithin(*anova, "method", false);
  auto tcsv = c.writer.Open(c.file_prefix + "_tukey.csv");
  tcsv << "a,b,diff,lwr,upr,p_adj\n";
  c.md << "\nTukey HSD on method (univariate error of the method effect, df = " << tk.df << "):\n\n"
       << "| pair | diff | 95 % CI | p adj |\n|---|---|---|---|\n";
  for (const auto& pr : tk.pairs) {
    c.md << fmt::format("| {} - {} | {:.2f} | [{:.2f}, {:.2f}] | {}{} |\n", pr.a, pr.b, pr.diff,
                        pr.lwr, pr.upr, P(pr.p_adj), Stars(pr.p_adj));
    tcsv << fmt::format("{},{},{:.10g},{:.10g},{:.10g},{:.10g}\n", pr.a, pr.b, pr.diff, pr.lwr,
                        pr.upr, pr.p_adj);
  }
  if (!c.figures) return;
  const auto base = c.writer.Path(c.file_prefix + "_methods");
  c.writer.Add(DrawBarChart(MethodChart(c, tk), base));
  c.md << "\n![" << c.criterion << " by method](" << fs::path(base).filename().string() << ".png)\n"
       << "\n(Error bars: " << kWithinCiLabel << " of the participants' method means; "
       << "* p < 0.05, ** p < 0.01, Tukey HSD.)\n";
}

void RunShapiro(AnalysisContext& c) {
  std::string why;
  if (const RmAnovaResult* anova = c.Anova(&why)) {
    ResidualNormality(c.md, c.writer, c.file_prefix, *anova, c.correction, c.figures,
                      fmt::format("{}: {} residuals", c.proto.title, c.criterion));
  } else {
    NotRun(c.md, "shapiro", "it tests the repeated-measures ANOVA's residuals: " + why);
  }
  c.md << "\n| method | boxplot outliers (raw ratings, 1.5 IQR) |\n|---|---|\n";
  for (const auto& me : c.methods) {
    const auto raw = c.ratings.Where({{"method", me}});
    c.md << fmt::format("| {} | {} of {} |\n", me,
                        Outliers(raw.y, QuartileRule::kHinges).outliers.size(), raw.rows());
  }
}

}  // namespace

Analysis RmAnovaAnalysis() {
  return {"rm-anova", "repeated-measures ANOVA (afex) with Mauchly's test and GG/HF corrections",
          Analysis::Scope::kCriterion, RunRmAnova};
}

Analysis TukeyAnalysis() {
  return {"tukey", "Tukey HSD on method with the ANOVA's pooled error, and the method bar chart",
          Analysis::Scope::kCriterion, RunTukey};
}

Analysis ShapiroAnalysis() {
  return {"shapiro", "Shapiro-Wilk on the ANOVA's residuals with a Q-Q plot; outlier counts",
          Analysis::Scope::kCriterion, RunShapiro};
}

}  // namespace hapticlab::stats
