// The `lmm` analysis: the protocol's [analysis] lmm_formula fitted to every rating of the
// criterion (no averaging), its type 3 F table, variance components and, when `shapiro` is
// requested too, the normality of its conditional residuals (y - Xb - Zu, R's
// residuals(lmer)).

#include <fmt/format.h>

#include <algorithm>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/stats/analysis.hpp"
#include "hapticlab/stats/lmm.hpp"
#include "report_internal.hpp"

namespace hapticlab::stats {

using namespace report_internal;

namespace {

void WriteLmm(AnalysisContext& c, const LmmResult& m) {
  auto csv = c.writer.Open(c.file_prefix + "_lmm.csv");
  csv << "kind,name,estimate_or_F,se,num_df,den_df,t,p\n";
  c.md << "| term | df | F | p |\n|---|---|---|---|\n";
  for (const auto& t : m.anova) {
    c.md << fmt::format("| {}{} | {:.0f}, {:.2f} | {:.3f} | {} |\n", t.term, t.p < 0.05 ? "*" : "",
                        t.num_df, t.den_df, t.F, P(t.p));
    csv << fmt::format("F,{},{:.10g},,{:.0f},{:.10g},,{:.10g}\n", t.term, t.F, t.num_df, t.den_df,
                       t.p);
  }
  for (const auto& f : m.fixed)
    csv << fmt::format("coefficient,{},{:.10g},{:.10g},1,{:.10g},{:.10g},{:.10g}\n", f.name,
                       f.estimate, f.se, f.df, f.t, f.p);
  c.md << "\n| random effect | SD |\n|---|---|\n";
  for (const auto& g : m.random)
    for (std::size_t i = 0; i < g.names.size(); ++i)
      c.md << fmt::format("| {} {} | {:.3f} |\n", g.group, g.names[i], g.sd[i]);
  c.md << fmt::format("| residual | {:.3f} |\n", m.sigma);
  if (m.singular)
    c.md << "\nBoundary (singular) fit: a variance is 0 or a correlation is +-1; simplify "
            "the random terms.\n";
  if (!m.converged) c.md << "\nThe optimizer did not converge; the numbers above are unreliable.\n";
}

void RunLmm(AnalysisContext& c) {
  c.md << "\nLinear mixed model `" << c.proto.lmm_formula
       << "` (REML, lme4's fit; Satterthwaite df, type 3 tests with sum-to-zero contrasts, as "
          "lmerTest / afex::mixed):\n\n";
  LmmResult m;
  try {
    m = FitLmm(c.ratings, c.proto.lmm_formula);
  } catch (const InputError& e) {
    c.md << "Not fitted: " << e.what() << "\n";
    return;
  }
  WriteLmm(c, m);
  if (std::find(c.requested.begin(), c.requested.end(), "shapiro") == c.requested.end()) return;
  std::vector<Conclusion> conclusions;
  for (const auto& t : m.anova) conclusions.push_back({t.term, t.p});
  ResidualNormality(c.md, c.writer, c.file_prefix + "_lmm", m.residuals,
                    "the mixed model's conditional residuals (each rating minus its fixed and "
                    "random-effect prediction, as R's `residuals(lmer)`",
                    conclusions, "a rank-based test or a transformed response", c.figures,
                    fmt::format("{}: {} mixed-model residuals", c.proto.title, c.criterion));
}

}  // namespace

Analysis LmmAnalysis() {
  return {"lmm",
          "linear mixed model of [analysis] lmm_formula on every rating (lme4, lmerTest); with "
          "`shapiro`, normality of its conditional residuals",
          Analysis::Scope::kCriterion, RunLmm};
}

}  // namespace hapticlab::stats
