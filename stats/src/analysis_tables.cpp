// Descriptive and rank-based analyses: `aggregate` (the score tables of Tables 4.1, 5.4,
// 5.5), `kruskal` (Kruskal-Wallis on the cell means) and `correlation` (overall similarity
// against the other criteria, Table 4.2).

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <tuple>

#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/stats/analysis.hpp"
#include "hapticlab/stats/descriptive.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "report_internal.hpp"

namespace hapticlab::stats {

using namespace report_internal;

namespace {

void RunAggregate(AnalysisContext& c) {
  auto& agg = c.StudyCsv(Safe(c.study) + "_aggregate.csv",
                         "criterion,group,material,method,mean,sd,n,ratio_to_upper\n");
  AggregateTables(c.md, agg, c.proto, c.criterion, c.ratings, c.methods, c.materials, c.upper);
}

void RunKruskal(AnalysisContext& c) {
  const std::string by = c.methods.size() >= 2 ? "method" : "material";
  const auto cells = c.ratings.Average({"participant", "method", "material"});
  if (cells.Levels(by).size() < 2)
    return NotRun(c.md, "kruskal", "it needs two or more methods or materials");
  const auto kw = KruskalWallis(cells, by);
  c.md << fmt::format("\nKruskal-Wallis on cell means by {}: H({:.0f}) = {:.2f}, {}.\n", by, kw.df,
                      kw.H, PEq(kw.p));
}

// Per main-phase trial (participant, material, comparison, method, repetition) its rating of
// every criterion; trials rated on every criterion give columns overall, min, max, mean.
std::map<std::string, std::vector<double>> CriterionColumns(const protocols::Protocol& proto,
                                                            const LongTable& main) {
  std::map<std::tuple<std::string, std::string, std::string, std::string, std::string>,
           std::map<std::string, double>>
      trials;
  const std::size_t participant = main.Key("participant"), material = main.Key("material"),
                    comparison = main.Key("comparison"), method = main.Key("method"),
                    repetition = main.Key("repetition"), criterion = main.Key("criterion");
  for (std::size_t i = 0; i < main.rows(); ++i)
    trials[{main.keys[participant][i], main.keys[material][i], main.keys[comparison][i],
            main.keys[method][i], main.keys[repetition][i]}][main.keys[criterion][i]] = main.y[i];
  std::map<std::string, std::vector<double>> col;
  for (const auto& [k, m] : trials) {
    if (m.size() != proto.criteria.size()) continue;
    double mn = 1e300, mx = -1e300, sum = 0;
    for (const auto& crit : proto.criteria) {
      col[crit].push_back(m.at(crit));
      if (crit == "overall") continue;
      mn = std::min(mn, m.at(crit));
      mx = std::max(mx, m.at(crit));
      sum += m.at(crit);
    }
    col["min"].push_back(mn);
    col["max"].push_back(mx);
    col["mean"].push_back(sum / static_cast<double>(proto.criteria.size() - 1));
  }
  return col;
}

void RunCorrelation(AnalysisContext& c) {
  const auto& criteria = c.proto.criteria;
  c.md << "\n### Correlation of overall similarity (Table 4.2)\n";
  if (!std::count(criteria.begin(), criteria.end(), "overall") || criteria.size() < 2)
    return NotRun(c.md, "correlation",
                  "it needs an `overall` criterion and at least one other criterion");
  auto col = CriterionColumns(c.proto, c.ratings);
  if (col["overall"].size() < 3)
    return NotRun(
        c.md, "correlation",
        fmt::format("it needs three or more main-phase trials rated on every criterion ({} so far)",
                    col["overall"].size()));
  c.md << fmt::format(
      "\nPearson r of each main-phase trial's overall rating with its rating on each other "
      "criterion and with the lowest (min), highest (max) and mean of those ratings; n = {} "
      "trials rated on every criterion, each one point (p treats the trials as independent, "
      "though each participant rated several).\n",
      col["overall"].size());
  c.md << "\n| with | Pearson r | p |\n|---|---|---|\n";
  for (const auto& [name, v] : col) {
    if (name == "overall") continue;
    const auto r = Pearson(col["overall"], v);
    c.md << fmt::format("| {} | {:.3f} | {} |\n", name, r.r, P(r.p));
  }
}

}  // namespace

Analysis AggregateAnalysis() {
  return {"aggregate", "mean, SD and n per method x material, and the ratio to the upper limit",
          Analysis::Scope::kCriterion, RunAggregate};
}

Analysis KruskalAnalysis() {
  return {"kruskal", "Kruskal-Wallis on the cell means by method (by material with one method)",
          Analysis::Scope::kCriterion, RunKruskal};
}

Analysis CorrelationAnalysis() {
  return {"correlation", "Pearson correlation of overall similarity with the other criteria",
          Analysis::Scope::kStudy, RunCorrelation};
}

}  // namespace hapticlab::stats
