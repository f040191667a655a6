// The report's shared helpers and tables (report_internal.hpp).
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
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/descriptive.hpp"
#include "hapticlab/stats/distributions.hpp"
#include "hapticlab/stats/lmm.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "hapticlab/stats/plot.hpp"
#include "hapticlab/stats/psychometric_report.hpp"
#include "hapticlab/stats/report.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/stats/tukey.hpp"
#include "report_internal.hpp"

namespace hapticlab::stats::report_internal {

std::string P(double p) { return p < 0.001 ? "< 0.001" : fmt::format("{:.3f}", p); }
// "p < 0.001" or "p = 0.020", for sentences.
std::string PEq(double p) { return p < 0.001 ? "p < 0.001" : fmt::format("p = {:.3f}", p); }
std::string Stars(double p) { return p < 0.01 ? "**" : p < 0.05 ? "*" : ""; }
std::string Safe(const std::string& s) {
  std::string o;
  for (char c : s) o += std::isalnum(static_cast<unsigned char>(c)) || c == '-' ? c : '_';
  return o;
}

// Mean and 95 % CI half-width of participant means (the error bars of Figs. 5.7/5.8).
std::pair<double, double> MeanCi(const LongTable& t) {
  const auto per = t.Average({"participant"});
  if (per.rows() == 0) return {NAN, NAN};
  const auto d = Describe(per.y);
  return {d.mean, d.n > 1 ? d.ci95_hi - d.mean : NAN};
}

// Levels of `present` in the protocol's order (`order`), then any others (sorted).
std::vector<std::string> InProtocolOrder(const std::vector<std::string>& order,
                                         const std::vector<std::string>& present) {
  std::vector<std::string> out;
  for (const auto& x : order)
    if (std::find(present.begin(), present.end(), x) != present.end()) out.push_back(x);
  for (const auto& x : present)
    if (std::find(out.begin(), out.end(), x) == out.end()) out.push_back(x);
  return out;
}

// Aggregate tables in the layout of the dissertation's Tables 5.4/5.5: methods as rows in
// protocol order, materials as columns in protocol order, one table per material group.
void AggregateTables(std::ostream& md, std::ostream& agg, const protocols::Protocol& proto,
                     const std::string& crit, const LongTable& cm,
                     const std::vector<std::string>& methods,
                     const std::vector<std::string>& materials, double upper) {
  std::vector<std::string> groups;  // in the order the protocol first names them
  std::map<std::string, std::vector<std::string>> by_group;
  for (const auto& ma : materials) {
    const auto* m = proto.FindMaterial(ma);
    const std::string g = m ? m->group : "";
    if (!by_group.count(g)) groups.push_back(g);
    by_group[g].push_back(ma);
  }
  md << "\nMean " << crit << " similarity (methods x materials, the layout of Tables 5.4/5.5)"
     << (std::isfinite(upper) ? "; in parentheses the ratio to the upper limit" : "") << ":\n";
  for (const auto& g : groups) {
    if (groups.size() > 1 || !g.empty()) md << "\n**" << (g.empty() ? "other" : g) << "**\n";
    md << "\n| method |";
    for (const auto& ma : by_group[g]) md << " " << ma << " |";
    md << "\n|---|";
    for (std::size_t i = 0; i < by_group[g].size(); ++i) md << "---|";
    md << "\n";
    for (const auto& me : methods) {
      md << "| " << me << " |";
      for (const auto& ma : by_group[g]) {
        const auto cell = cm.Where({{"material", ma}, {"method", me}});
        if (cell.rows() == 0) {
          md << " |";
          continue;
        }
        const auto ds = Describe(cell.y);
        const double ratio = std::isfinite(upper) ? ds.mean / upper : NAN;
        md << fmt::format(" {:.2f}{} |", ds.mean,
                          std::isfinite(ratio) ? fmt::format(" ({:.2f})", ratio) : "");
        agg << fmt::format("{},{},{},{},{:.6f},{:.6f},{},{}\n", crit, g, ma, me, ds.mean, ds.sd,
                           ds.n, std::isfinite(ratio) ? fmt::format("{:.6f}", ratio) : "");
      }
      md << "\n";
    }
  }
}

// The rmANOVA table with Mauchly's test beside each effect. One rule decides significance
// (UsedP under `correction`): the star, the df and p columns and every sentence follow it.
void AnovaTable(std::ostream& md, std::ostream& csv, const RmAnovaResult& a,
                Correction correction) {
  const bool corrected = correction != Correction::kNone;
  const std::string cname = correction == Correction::kGG ? "Greenhouse-Geisser" : "Huynh-Feldt";
  md << "\nRepeated-measures ANOVA (" << a.subjects.size() << " participants"
     << (a.dropped_subjects.empty()
             ? ""
             : fmt::format(", {} dropped for missing cells", a.dropped_subjects.size()))
     << "):\n\n";
  // Every dropped participant named, with the cells it lacks.
  for (std::size_t i = 0; i < a.dropped_subjects.size(); ++i)
    md << "- dropped " << a.dropped_subjects[i] << ": " << a.dropped_reasons[i] << "\n";
  if (!a.dropped_subjects.empty()) md << "\n";
  md << "| factor | df | F | p | partial eta^2 | Mauchly W | p (Mauchly) | GG eps | HF eps |\n"
        "|---|---|---|---|---|---|---|---|---|\n";
  std::vector<std::string> notes;
  for (const auto& e : a.effects) {
    const bool within = !e.between_only;
    const bool testable = within && e.mauchly_defined && e.df1 > 1;
    const bool violated = testable && e.mauchly_p < 0.05;
    const double p_used = UsedP(e, correction), eps = UsedEpsilon(e, correction);
    const std::string df = eps == 1 ? fmt::format("{:.0f}, {:.0f}", e.df1, e.df2)
                                    : fmt::format("{:.2f}, {:.2f}", e.df1 * eps, e.df2 * eps);
    const std::string W = !within || e.df1 <= 1 ? "-"
                          : e.mauchly_defined   ? fmt::format("{:.3f}", e.mauchly_W)
                                                : "n/a";
    const std::string p_w = !within || e.df1 <= 1 ? "-"
                            : e.mauchly_defined   ? P(e.mauchly_p) + (violated ? " (violated)" : "")
                                                  : "n/a";
    md << fmt::format("| {}{} | {} | {} | {} | {:.3f} | {} | {} | {} | {} |\n", e.effect,
                      Stars(p_used).empty() ? "" : "*", df,
                      e.F < 1e5 ? fmt::format("{:.3f}", e.F) : fmt::format("{:.3g}", e.F),
                      P(p_used), e.pes, W, p_w, within ? fmt::format("{:.3f}", e.gg_epsilon) : "-",
                      within ? fmt::format("{:.3f}", e.hf_epsilon) : "-");
    const auto num = [&](double v) { return within ? fmt::format("{:.10g}", v) : std::string(); };
    csv << fmt::format(
        "{},{},{},{:.10g},{:.10g},{:.10g},{},{},{},{},{},{},{},{:.10g}\n", e.effect, e.df1, e.df2,
        e.F, e.p, e.pes, within && std::isfinite(e.mauchly_W) ? num(e.mauchly_W) : "",
        within && std::isfinite(e.mauchly_p) ? num(e.mauchly_p) : "", num(e.gg_epsilon),
        num(e.p_gg), num(e.hf_epsilon), num(e.p_hf), CorrectionName(correction), p_used);
    if (violated && corrected)
      notes.push_back(fmt::format(
          "**Sphericity violated** for {}: Mauchly's W = {:.3f}, {}. The {} correction is used "
          "(epsilon = {:.3f}, corrected {}).",
          e.effect, e.mauchly_W, PEq(e.mauchly_p), cname, eps, PEq(p_used)));
    else if (violated)
      notes.push_back(fmt::format(
          "**Sphericity violated** for {}: Mauchly's W = {:.3f}, {}. The uncorrected p above "
          "assumes sphericity (`correction = \"none\"`); the Greenhouse-Geisser corrected p is "
          "{:.3f}.",
          e.effect, e.mauchly_W, PEq(e.mauchly_p), e.p_gg));
    else if (within && e.df1 > 1 && !e.mauchly_defined)
      notes.push_back(
          corrected
              ? fmt::format(
                    "Mauchly's test does not exist for {} (more levels than participants - 1): "
                    "sphericity cannot be tested, and the {} corrected p above is the one used "
                    "(epsilon = {:.3f}, {}).",
                    e.effect, cname, eps, PEq(p_used))
              : fmt::format(
                    "Mauchly's test does not exist for {} (more levels than participants - 1): "
                    "the uncorrected p above assumes a sphericity that cannot be tested "
                    "(`correction = \"none\"`); the Greenhouse-Geisser corrected p is {:.3f}.",
                    e.effect, e.p_gg));
  }
  if (corrected)
    md << fmt::format(
        "\nSignificance rule: an effect is marked * when its p < 0.05, where df and p of "
        "within-subject effects are {} corrected (afex's default; the protocol's `[analysis] "
        "correction = \"{}\"`), whatever Mauchly's test says, and between-subject effects "
        "need no correction. The uncorrected p is in the CSV. Mauchly's test is shown for "
        "factors with more than two levels (with two, sphericity holds trivially).\n",
        cname, CorrectionName(correction));
  else
    md << "\nSignificance rule: an effect is marked * when its uncorrected p < 0.05 (the "
          "protocol's `[analysis] correction = \"none\"`: sphericity is assumed). Mauchly's test "
          "is shown for factors with more than two levels (with two, sphericity holds "
          "trivially).\n";
  for (const auto& n : notes) md << "\n" << n << "\n";
}

}  // namespace hapticlab::stats::report_internal
