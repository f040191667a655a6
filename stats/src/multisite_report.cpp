// The report's "Sites" section (multisite.hpp): per-site means beside the pooled model, the
// site SD with its bootstrap interval, the forest plot and the replication summary.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/stats/multisite.hpp"
#include "hapticlab/stats/plot.hpp"
#include "report_internal.hpp"

namespace hapticlab::stats::report_internal {

namespace {

// Each participant's site (its sessions' smallest site code).
std::map<std::string, std::string> ParticipantSites(const db::Database& d, std::int64_t study) {
  std::map<std::string, std::string> out;
  for (const auto& p : d.Participants(study))
    for (const auto& se : d.Sessions(p.id)) {
      auto& s = out[p.code];
      if (s.empty() || se.site_code < s) s = se.site_code;
    }
  return out;
}

// `t` with a site key column from `sites` (by participant).
LongTable WithSite(const LongTable& t, const std::map<std::string, std::string>& sites) {
  LongTable out = t;
  out.key_names.push_back("site");
  out.keys.emplace_back();
  const auto& part = t.keys[t.Key("participant")];
  for (std::size_t r = 0; r < t.rows(); ++r) {
    const auto it = sites.find(part[r]);
    out.keys.back().push_back(it == sites.end() ? db::kDefaultSiteCode : it->second);
  }
  return out;
}

void MeansTable(std::ostream& md, const MultiSiteFit& f, const std::vector<std::string>& methods) {
  md << "\n| site | participants |";
  for (const auto& m : methods) md << " " << m << " |";
  md << " " << f.last << " - " << f.first << " [95 % CI] |\n|---|---|";
  for (std::size_t i = 0; i <= methods.size(); ++i) md << "---|";
  md << "\n";
  for (const auto& s : f.sites) {
    md << "| " << s.site << " | " << s.participants << " |";
    for (const auto& m : methods) {
      const auto& sm = f.site_means.at(s.site);
      md << (sm.count(m) ? fmt::format(" {:.2f} |", sm.at(m)) : " - |");
    }
    md << fmt::format(" {:.2f} [{:.2f}, {:.2f}] |\n", s.estimate, s.low, s.high);
  }
  md << "| pooled (LMM) | " << f.participants << " |";
  for (const auto& m : methods)
    md << (f.pooled_means.count(m) ? fmt::format(" {:.2f} |", f.pooled_means.at(m)) : " - |");
  md << fmt::format(" {:.2f} [{:.2f}, {:.2f}] |\n", f.pooled.estimate, f.pooled_low, f.pooled_high);
}

void Criterion(std::ostream& md, Writer& w, const protocols::Protocol& proto,
               const std::string& crit, const LongTable& cm,
               const std::vector<std::string>& methods, bool figures) {
  const MultiSiteFit f = FitMultiSite(cm, methods);
  md << "\n#### " << crit << " across sites\n\nLinear mixed model `" << f.formula
     << "` (REML; Satterthwaite df). Per-site rows: the participants' mean scores and their "
        "mean method difference with a 95 % t interval over participants; the pooled row: "
        "the raw means and the model's contrast of the two methods' marginal means.\n";
  MeansTable(md, f, methods);
  md << fmt::format(
      "\nSite SD {:.2f} points (95 % parametric-bootstrap percentile interval [{:.2f}, {:.2f}] "
      "from {} refits; lme4's confint(method = \"boot\")); residual SD {:.2f}.{}\n",
      f.site_sd, f.site_sd_low, f.site_sd_high, f.bootstrap_fits, f.model.sigma,
      f.model.singular ? " Boundary (singular) fit: a variance is 0 or a correlation +-1." : "");
  const auto orig = ShinOriginalEffect(proto.name, crit, f.first, f.last);
  if (orig)
    md << "\n**Replication summary.** " << ReplicationStatement(f, *orig);
  else
    md << "\nNo original value of this effect is on record for this protocol and criterion "
          "(the shin2019 ch. V.3 protocol's roughness and overall have one).\n";
  const std::string base = fmt::format("{}_{}_sites", Safe(proto.name), Safe(crit));
  auto csv = w.Open(base + ".csv");
  csv << "site,participants,effect,low,high\n";
  for (const auto& s : f.sites)
    csv << fmt::format("{},{},{:.10g},{:.10g},{:.10g}\n", s.site, s.participants, s.estimate, s.low,
                       s.high);
  csv << fmt::format("pooled,{},{:.10g},{:.10g},{:.10g}\n", f.participants, f.pooled.estimate,
                     f.pooled_low, f.pooled_high);
  if (!figures) return;
  ForestPlot fp{.title = crit + ": " + f.last + " - " + f.first + " by site",
                .x_label = "method effect [rating points]",
                .note =
                    "squares: site means of participant differences, 95% t CI; diamond: "
                    "pooled LMM contrast, 95% CI"};
  for (const auto& s : f.sites) fp.rows.push_back({s.site, s.estimate, s.low, s.high, false});
  fp.rows.push_back({"pooled", f.pooled.estimate, f.pooled_low, f.pooled_high, true});
  fp.vlines.emplace_back(0.0, "0");
  if (orig) fp.vlines.emplace_back(orig->effect, "original");
  w.Add(DrawForestPlot(fp, (std::filesystem::path(w.dir()) / base).string()));
  md << "\n![" << crit << " method effect by site](" << base << ".png)\n";
}

}  // namespace

std::string MultiSiteSection(const db::Database& d, std::int64_t study_id,
                             const protocols::Protocol& proto, const LongTable& study, Writer& w,
                             bool figures) {
  const LongTable all = WithSite(study, ParticipantSites(d, study_id));
  if (all.Levels("site").size() < 2) return "";
  std::ostringstream md;
  md << "\n### Sites\n\nSessions from " << all.Levels("site").size() << " sites ("
     << fmt::format("{}", fmt::join(all.Levels("site"), ", "))
     << "); the site is a random effect (docs/replication.md, \"Combining sites\").\n";
  std::vector<std::string> order;
  for (const auto& m : proto.methods) order.push_back(m.name);
  const LongTable main = all.Where({{"phase", "main"}});
  for (const auto& crit : proto.criteria) {
    const LongTable cm = main.Where({{"criterion", crit}});
    if (cm.rows() == 0) continue;
    try {
      Criterion(md, w, proto, crit, cm, order, figures);
    } catch (const InputError& e) {
      md << "\n#### " << crit << " across sites\n\nNot fitted: " << e.what() << "\n";
    }
  }
  return md.str();
}

}  // namespace hapticlab::stats::report_internal
