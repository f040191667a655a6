// The deviations-from-the-plan report section (replication/deviations.hpp).

#include "hapticlab/replication/deviations.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "hapticlab/db/database.hpp"
#include "hapticlab/protocols/canonical.hpp"

namespace hapticlab::replication {
namespace {

using nlohmann::json;

bool Has(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

std::string Short(const std::string& h) { return h.empty() ? "none" : h.substr(0, 12); }

// Sessions of the study: (participant code, provenance).
std::vector<std::pair<std::string, json>> SessionsOf(const db::Database& d, const db::Study& st) {
  std::vector<std::pair<std::string, json>> out;
  for (const auto& p : d.Participants(st.id))
    for (const auto& se : d.Sessions(p.id)) {
      auto prov = json::parse(se.provenance_json, nullptr, false);
      out.emplace_back(p.code, prov.is_object() ? prov : json::object());
    }
  return out;
}

// Sessions without the plan or under another one; protocol keys a session under the plan
// changed (recorded by `study run PROTOCOL --plan`; kept per session through `db merge`, which
// keeps one protocol text per study) unless the study's protocol already shows them; models
// that differ or were substituted.
void SessionDeviations(const Plan& plan, const db::Database& d, const db::Study& st,
                       const std::set<std::string>& study_changes, std::vector<Deviation>* out) {
  std::map<std::string, std::vector<std::string>> other_plan;     // hash -> participants
  std::map<std::string, std::vector<std::string>> changed_key;    // change -> participants
  std::map<std::string, std::vector<std::string>> substituted;    // text -> participants
  std::map<std::string, std::vector<std::string>> changed_model;  // text -> participants
  std::map<std::string, std::string> planned;
  for (const auto& m : plan.analysis.models) planned[m.material] = m.sha256;
  for (const auto& [code, prov] : SessionsOf(d, st)) {
    const std::string h = prov.value("plan_sha256", "");
    if (h != plan.plan_hash) other_plan[h].push_back(code);
    const json changes = prov.value("plan_protocol_changes", json::array());
    if (h == plan.plan_hash && changes.is_array())
      for (const auto& c : changes)
        if (c.is_string() && !study_changes.count(c.get<std::string>()))
          changed_key[c.get<std::string>()].push_back(code);
    const json subs = prov.value("substituted_models", json::object());
    const json hashes = prov.value("model_hashes", json::object());
    for (const auto& [material, hash] : hashes.items()) {
      if (!hash.is_string()) continue;
      const auto want = planned.find(material);
      const std::string site = prov.value("plan_site", "");
      if (subs.contains(material))
        substituted[fmt::format("{}: the site's own model (sha256 {}) replaces the plan's "
                                "(sha256 {}){}",
                                material, Short(hash.get<std::string>()),
                                Short(want == planned.end() ? "" : want->second),
                                site.empty() ? "" : " at site " + site)]
            .push_back(code);
      else if (want != planned.end() && want->second != hash.get<std::string>())
        changed_model[fmt::format("{}: model sha256 {}, the plan's {}", material,
                                  Short(hash.get<std::string>()), Short(want->second))]
            .push_back(code);
    }
  }
  const auto who = [](const std::vector<std::string>& codes) {
    return fmt::format("{} session(s): {}", codes.size(), fmt::join(codes, ", "));
  };
  for (const auto& [text, codes] : changed_key)
    out->push_back({"protocol key changed", text + " — " + who(codes)});
  for (const auto& [h, codes] : other_plan)
    out->push_back(
        {"session not under the plan",
         (h.empty() ? std::string("recorded without a plan") : "recorded under plan " + Short(h)) +
             " — " + who(codes)});
  for (const auto& [text, codes] : substituted)
    out->push_back({"material substituted", text + " — " + who(codes)});
  for (const auto& [text, codes] : changed_model)
    out->push_back({"model hash differs", text + " — " + who(codes)});
}

// Exclusion rules: a rule applied that the plan does not name, or one it names not applied.
void ExclusionDeviations(const Plan& plan, const db::Database& d, const db::Study& st,
                         const AnalyzeSettings& s, std::vector<Deviation>* out) {
  bool human = false;
  std::map<std::string, std::pair<std::size_t, std::size_t>> by;  // code -> (person, simulated)
  for (const auto& p : d.Participants(st.id))
    for (const auto& se : d.Sessions(p.id))
      for (const auto& tr : d.Trials(se.id))
        for (const auto& r : d.Ratings(tr.id)) {
          const bool sim = r.source == db::kRaterSimulated;
          human = human || !sim;
          (sim ? by[p.code].second : by[p.code].first) += 1;
        }
  if (!human) return;  // a simulated study: the rule leaves nothing out
  std::size_t simulated = 0;
  std::vector<std::string> whole;
  for (const auto& [code, n] : by) {
    simulated += n.second;
    if (n.first == 0 && n.second > 0) whole.push_back(code);
  }
  if (simulated == 0) return;
  const bool planned = Has(plan.analysis.exclusions, kRuleSimulatedRatings);
  if (!s.include_simulated && !planned)
    out->push_back(
        {"exclusion not in the plan",
         fmt::format("rule {} left out {} simulated ratings{}", kRuleSimulatedRatings, simulated,
                     whole.empty()
                         ? std::string()
                         : fmt::format("; participants excluded: {}", fmt::join(whole, ", ")))});
  if (s.include_simulated && planned)
    out->push_back({"exclusion rule not applied",
                    fmt::format("the plan's rule {} was not applied (--include-simulated): {} "
                                "simulated ratings kept",
                                kRuleSimulatedRatings, simulated)});
}

}  // namespace

std::vector<Deviation> FindDeviations(const Plan& plan, const db::Database& d, const db::Study& st,
                                      const AnalyzeSettings& s) {
  std::vector<Deviation> out;
  std::set<std::string> study_changes;
  for (const auto& c : protocols::CanonicalDifferences(plan.protocol_text, st.protocol_toml)) {
    out.push_back({"protocol key changed", c.Describe()});
    study_changes.insert(c.Describe());
  }
  const auto proto = protocols::ParseProtocol(st.protocol_toml, "(protocol of " + st.name + ")");
  for (const auto& t : proto.analyses)
    if (!Has(plan.analysis.tests, t))
      out.push_back({"analysis not in the plan", t + " (exploratory)"});
  for (const auto& t : plan.analysis.tests)
    if (!Has(proto.analyses, t)) out.push_back({"planned analysis not run", t});
  const std::string correction = s.correction.empty() ? proto.correction : s.correction;
  if (correction != plan.analysis.correction)
    out.push_back({"correction changed", fmt::format("sphericity correction {}, the plan's {}",
                                                     correction, plan.analysis.correction)});
  SessionDeviations(plan, d, st, study_changes, &out);
  ExclusionDeviations(plan, d, st, s, &out);
  return out;
}

std::string DeviationsSection(const Plan& plan, const db::Database& d, const db::Study& st,
                              const AnalyzeSettings& s) {
  const auto& a = plan.analysis;
  std::string md = fmt::format("\n### Preregistration: plan `{}`\n\n", plan.plan_hash);
  if (st.name != a.study)
    return md + fmt::format("This study is not the plan's (`{}`): it is not compared with it.\n",
                            a.study);
  const auto proto = protocols::ParseProtocol(st.protocol_toml, "(protocol of " + st.name + ")");
  std::vector<std::string> pre, exploratory;
  for (const auto& t : proto.analyses) (Has(a.tests, t) ? pre : exploratory).push_back(t);
  md += fmt::format(
      "Plan frozen with HapticLab {} (docs/replication.md). Primary outcome: the {} effect on "
      "{} (repeated-measures ANOVA, alpha {}){}.\n\n",
      a.software, a.primary_effect, a.primary_criterion, a.alpha,
      a.power && a.power_participants_needed > 0
          ? fmt::format("; the plan's power analysis asked for {} participants (observer {})",
                        a.power_participants_needed, a.power_observer)
          : "");
  md += fmt::format("- Preregistered analyses (in the plan): {}\n",
                    pre.empty() ? std::string("none") : fmt::format("{}", fmt::join(pre, ", ")));
  md += fmt::format(
      "- Exploratory analyses (not in the plan; read their results as "
      "exploratory): {}\n",
      exploratory.empty() ? std::string("none") : fmt::format("{}", fmt::join(exploratory, ", ")));
  std::size_t sessions = 0, under = 0;
  for (const auto& [code, prov] : SessionsOf(d, st)) {
    ++sessions;
    under += prov.value("plan_sha256", "") == plan.plan_hash;
  }
  md += fmt::format("- Sessions recorded under this plan: {} of {}\n", under, sessions);
  const auto devs = FindDeviations(plan, d, st, s);
  md += "\n#### Deviations from the plan\n\n";
  if (devs.empty()) return md + "None: the study ran and is analysed as planned.\n";
  md += "| # | kind | deviation |\n|---|---|---|\n";
  for (std::size_t i = 0; i < devs.size(); ++i) {
    std::string what = devs[i].what;
    std::replace(what.begin(), what.end(), '|', '/');
    md += fmt::format("| {} | {} | {} |\n", i + 1, devs[i].kind, what);
  }
  return md;
}

}  // namespace hapticlab::replication
