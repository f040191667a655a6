// The `grouping` analysis (ch. IV.5.2, Fig. 4.5): the materials of a single method against the
// real-real limits of the reference phase, Kruskal-Wallis then Dunn-Bonferroni letters; the
// letters and the limits go onto the criterion's per-material bar chart.

#include <fmt/format.h>

#include <algorithm>

#include "hapticlab/stats/analysis.hpp"
#include "hapticlab/stats/descriptive.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "report_internal.hpp"

namespace hapticlab::stats {

using namespace report_internal;

namespace {

// The criterion's ratings with the limits' ratings added as two more "materials".
LongTable WithLimits(const AnalysisContext& c) {
  LongTable g = c.ratings;
  for (const auto& [limit, t] :
       {std::pair{"upper limit", &c.same}, std::pair{"lower limit", &c.different}})
    for (std::size_t i = 0; i < t->rows(); ++i) {
      for (std::size_t k = 0; k < g.key_names.size(); ++k)
        g.keys[k].push_back(g.key_names[k] == "material" ? limit : t->keys[k][i]);
      g.y.push_back(t->y[i]);
    }
  return g;
}

// The letters above the materials, and the limits as two more bar groups.
void MarkChart(BarChart& bm, const std::vector<LimitGroup>& letters, const AnalysisContext& c) {
  for (const auto& l : letters) {
    const auto it = std::find(bm.groups.begin(), bm.groups.end(), l.material);
    if (it == bm.groups.end()) continue;
    bm.group_marks.resize(bm.groups.size());
    bm.group_marks[static_cast<std::size_t>(it - bm.groups.begin())] = l.letter;
  }
  bm.groups.push_back("lower limit");
  bm.groups.push_back("upper limit");
  for (auto& s : bm.series) {
    s.mean.push_back(c.lower);
    s.err.push_back(Describe(c.different.y).se);
    s.mean.push_back(c.upper);
    s.err.push_back(Describe(c.same.y).se);
  }
  bm.error_label += "; limits: SE";
}

void RunGrouping(AnalysisContext& c) {
  if (c.methods.size() != 1)
    return NotRun(c.md, "grouping",
                  fmt::format("it compares the materials of a single method against the "
                              "real-real limits (ch. IV.5.2), and this study has {} methods (see "
                              "Tukey HSD for them)",
                              c.methods.size()));
  if (!c.same.rows() || !c.different.rows())
    return NotRun(c.md, "grouping",
                  "it needs the real-real limits: a reference phase with both same-material and "
                  "different-material pairs");
  const LongTable g = WithLimits(c);
  const auto kw = KruskalWallis(g, "material");
  const auto letters = GroupAgainstLimits(g, "material", "upper limit", "lower limit");
  c.md << fmt::format(
      "\nKruskal-Wallis over materials and limits: H({:.0f}) = {:.2f}, p = {}. Dunn-Bonferroni "
      "letters: A differs from the lower limit only, B from the upper only, C from neither, D "
      "from both.\n\n| material | letter | p adj vs upper | p adj vs lower |\n|---|---|---|---|\n",
      kw.df, kw.H, P(kw.p));
  auto csv = c.writer.Open(c.file_prefix + "_grouping.csv");
  csv << "material,letter,p_adj_vs_upper,p_adj_vs_lower\n";
  for (const auto& l : letters) {
    c.md << fmt::format("| {} | {} | {} | {} |\n", l.material, l.letter, P(l.p_adj_vs_upper),
                        P(l.p_adj_vs_lower));
    csv << fmt::format("{},{},{:.10g},{:.10g}\n", l.material, l.letter, l.p_adj_vs_upper,
                       l.p_adj_vs_lower);
  }
  if (c.material_chart) MarkChart(*c.material_chart, letters, c);
}

}  // namespace

Analysis GroupingAnalysis() {
  return {"grouping",
          "materials of one method against the real-real limits: Kruskal-Wallis, Dunn letters",
          Analysis::Scope::kCriterion, RunGrouping};
}

}  // namespace hapticlab::stats
