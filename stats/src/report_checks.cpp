// The report's assumption check (report_internal.hpp): normality of the rmANOVA's residuals,
// said as advice only where a conclusion is at stake, with a Q-Q figure.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <ostream>
#include <string>
#include <tuple>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/plot.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/stats/within_ci.hpp"
#include "report_internal.hpp"

namespace hapticlab::stats::report_internal {

void MaterialSeries(BarChart& chart, const LongTable& cm, const std::vector<std::string>& methods,
                    const std::vector<std::string>& materials) {
  // Within-subject CIs need cells that vary within participants: two or more of them.
  const bool within = methods.size() * materials.size() >= 2;
  std::vector<WithinCi> ci;
  if (within) ci = WithinSubjectCi(cm, "participant", {"method", "material"});
  chart.error_label = within ? kWithinCiLabel : "95% CI of participant means";
  chart.series.clear();
  for (const auto& me : methods) {
    BarSeries s{me, {}, {}};
    for (const auto& ma : materials) {
      double m = NAN, e = NAN;
      if (within) {
        for (const auto& c : ci)
          if (c.cell[0] == me && c.cell[1] == ma) std::tie(m, e) = std::pair{c.mean, c.half_width};
      } else {
        std::tie(m, e) = MeanCi(cm.Where({{"material", ma}, {"method", me}}));
      }
      s.mean.push_back(m);
      s.err.push_back(e);
    }
    chart.series.push_back(std::move(s));
  }
}

void ResidualNormality(std::ostream& md, Writer& w, const std::string& base_name,
                       const std::vector<double>& e, const std::string& what,
                       const std::vector<Conclusion>& conclusions, const std::string& advice,
                       bool figures, const std::string& title) {
  md << fmt::format("\nNormality of {}, {} residuals): ", what, e.size());
  ShapiroResult s;
  try {
    s = ShapiroWilk(e);
  } catch (const InputError&) {
    md << "not tested (fewer than 3 residuals, more than 5000, or no spread).\n";
    return;
  }
  md << fmt::format("Shapiro-Wilk W = {:.4f}, {}.\n", s.W, PEq(s.p));
  if (figures) {
    QqPlot q;
    q.title = title;
    q.y_label = "residual";
    q.sample = e;
    const auto base = (fs::path(w.dir()) / (base_name + "_qq")).string();
    w.Add(DrawQqPlot(q, base));
    md << "\n![Q-Q plot of the residuals](" << fs::path(base).filename().string()
       << ".png)\n\n(Normal Q-Q plot of the residuals; the line passes through the quartiles.)\n";
  }
  if (s.p >= 0.05) return;
  // A conclusion is at stake where a moderate departure could move its p across 0.05.
  std::vector<std::string> at_stake;
  for (const auto& c : conclusions)
    if (c.p >= kStakeLow && c.p < kStakeHigh)
      at_stake.push_back(fmt::format("{} ({})", c.effect, PEq(c.p)));
  if (at_stake.empty()) {
    md << fmt::format(
        "\nThe residuals depart from normality, but no effect's p lies between {} and {}, where "
        "such a departure could change a conclusion at 0.05.\n",
        kStakeLow, kStakeHigh);
    return;
  }
  std::string list;
  for (std::size_t i = 0; i < at_stake.size(); ++i) list += (i ? ", " : "") + at_stake[i];
  md << "\nAdvice: the residuals depart from normality and the conclusion on " << list
     << " lies near the 0.05 threshold; confirm it with " << advice << " before relying on it.\n";
}

void ResidualNormality(std::ostream& md, Writer& w, const std::string& base_name,
                       const RmAnovaResult& a, Correction correction, bool figures,
                       const std::string& title) {
  std::vector<Conclusion> conclusions;
  for (const auto& ef : a.effects) conclusions.push_back({ef.effect, UsedP(ef, correction)});
  ResidualNormality(md, w, base_name, AnovaResiduals(a),
                    "the ANOVA's residuals (as afex's `residuals()`: each participant's cell mean "
                    "minus the cell's mean",
                    conclusions,
                    "a model that does not rest on normal cell means (the linear mixed model "
                    "`lmm` on every rating, or a rank-based test)",
                    figures, title);
}

}  // namespace hapticlab::stats::report_internal
