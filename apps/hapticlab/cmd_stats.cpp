// hapticlab stats: the statistics on any long-format CSV, without a study database.

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "cmd_stats_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/stats/tukey.hpp"
#include "stats_commands.hpp"

namespace hapticlab::cli {
namespace {

using nlohmann::json;
using stats_cmd::AddCommon;
using stats_cmd::Common;
using stats_cmd::Fitted;
using stats_cmd::Load;
using stats_cmd::Num;
using stats_cmd::RequireFinite;

// Every statistic of an ANOVA table the commands print (sphericity fields of within terms).
std::vector<std::pair<std::string, double>> AnovaValues(const stats::RmAnovaResult& r) {
  std::vector<std::pair<std::string, double>> v;
  for (const auto& e : r.effects) {
    for (const auto& [n, x] :
         {std::pair{"F", e.F}, std::pair{"p", e.p}, std::pair{"pes", e.pes}, std::pair{"SS", e.SS},
          std::pair{"SS_error", e.SS_error}, std::pair{"MSE", e.MSE}})
      v.emplace_back(e.effect + " " + n, x);
    if (e.between_only) continue;
    if (e.mauchly_defined) {
      v.emplace_back(e.effect + " Mauchly W", e.mauchly_W);
      v.emplace_back(e.effect + " Mauchly p", e.mauchly_p);
    }
    // The Huynh-Feldt epsilon itself may be undefined (0/0 with two subjects, NaN in R too;
    // JSON null): p HF then uses the Greenhouse-Geisser epsilon and is checked.
    for (const auto& [n, x] : {std::pair{"GG epsilon", e.gg_epsilon}, std::pair{"p GG", e.p_gg},
                               std::pair{"p HF", e.p_hf}})
      v.emplace_back(e.effect + " " + n, x);
  }
  return v;
}

// --missing for the ANOVA commands: a missing (empty or NA) response is an error, or drops
// its subject (named), as afex does.
void AddMissing(CLI::App* cmd, const std::shared_ptr<Common>& c) {
  auto* o = cmd->add_option_function<std::string>(
      "--missing", [c](const std::string& v) { c->allow_missing = v == "drop-subject"; },
      "An empty or NA response: 'error' (default; names file, line and column) or 'drop-subject'\n"
      "(its cell counts as unobserved, so the subject is dropped and named, as afex does)");
  o->check(CLI::IsMember({"error", "drop-subject"}));
}

// Names every dropped subject and why (text output).
void PrintDropped(const stats::RmAnovaResult& r) {
  for (std::size_t i = 0; i < r.dropped_subjects.size(); ++i)
    fmt::print("dropped {}: {}\n", r.dropped_subjects[i], r.dropped_reasons[i]);
}

json DroppedJson(const stats::RmAnovaResult& r) {
  json d = json::array();
  for (std::size_t i = 0; i < r.dropped_subjects.size(); ++i)
    d.push_back({{"subject", r.dropped_subjects[i]}, {"reason", r.dropped_reasons[i]}});
  return d;
}

struct RmAnovaArgs {
  std::shared_ptr<Common> c = std::make_shared<Common>();
  std::string subject, within, between, correction = "GG";
};

// The residuals' normality (afex's residuals(), as performance::check_normality); null when
// Shapiro-Wilk is undefined for them.
json ResidualNormality(const stats::RmAnovaResult& r) {
  json normality;
  try {
    const auto sw = stats::ShapiroWilk(stats::AnovaResiduals(r));
    if (std::isfinite(sw.W) && std::isfinite(sw.p))
      normality = {{"test", "Shapiro-Wilk"}, {"n", sw.n}, {"W", sw.W}, {"p", sw.p}};
  } catch (const InputError&) {  // < 3 or > 5000 residuals, or no spread
  }
  return normality;
}

json RmAnovaJson(const stats::RmAnovaResult& r, stats::Correction corr,
                 const std::string& correction, const json& normality) {
  json effects = json::array();
  for (const auto& e : r.effects) {
    json j = {{"effect", e.effect},
              {"df1", e.df1},
              {"df2", e.df2},
              {"F", e.F},
              {"p", e.p},
              {"pes", e.pes},
              {"SS", e.SS},
              {"SS_error", e.SS_error},
              {"MSE", e.MSE},
              {"p_used", stats::UsedP(e, corr)},
              {"between_only", e.between_only}};
    if (!e.between_only) {  // a between-subjects term has no sphericity question
      j["mauchly_W"] = Num(e.mauchly_W);
      j["mauchly_p"] = Num(e.mauchly_p);
      j["mauchly_p_firstorder"] = Num(e.mauchly_p_firstorder);
      j["gg_epsilon"] = Num(e.gg_epsilon);
      j["p_gg"] = Num(e.p_gg);
      j["hf_epsilon"] = Num(e.hf_epsilon);
      j["p_hf"] = Num(e.p_hf);
    }
    effects.push_back(std::move(j));
  }
  return json{{"effects", effects},
              {"correction", correction},
              {"residual_normality", normality},
              {"subjects", r.subjects.size()},
              {"dropped_subjects", r.dropped_subjects},
              {"dropped", DroppedJson(r)}};
}

// The ANOVA table: every term, with the sphericity columns for within terms.
void PrintAnovaTable(const stats::RmAnovaResult& r) {
  fmt::print("{:<24} {:>5} {:>7} {:>10} {:>11} {:>7} {:>9} {:>9} {:>7} {:>10} {:>7} {:>10}\n",
             "effect", "df1", "df2", "F", "p", "pes", "Mauchly W", "p", "GG eps", "p GG", "HF eps",
             "p HF");
  for (const auto& e : r.effects) {
    if (e.between_only) {  // between-subjects term: no sphericity question
      fmt::print("{:<24} {:>5.0f} {:>7.0f} {:>10.4f} {:>11.4g} {:>7.3f}\n", e.effect, e.df1, e.df2,
                 e.F, e.p, e.pes);
      continue;
    }
    fmt::print(
        "{:<24} {:>5.0f} {:>7.0f} {:>10.4f} {:>11.4g} {:>7.3f} {:>9.4g} {:>9.4g} {:>7.4f} "
        "{:>10.4g} {:>7.4f} {:>10.4g}\n",
        e.effect, e.df1, e.df2, e.F, e.p, e.pes, e.mauchly_W, e.mauchly_p, e.gg_epsilon, e.p_gg,
        e.hf_epsilon, e.p_hf);
  }
}

void PrintRmAnova(const stats::RmAnovaResult& r, bool between, stats::Correction corr,
                  const std::string& correction, const json& normality) {
  fmt::print("{} subjects{}\n", r.subjects.size(),
             r.dropped_subjects.empty()
                 ? ""
                 : fmt::format(" ({} dropped for a missing cell)", r.dropped_subjects.size()));
  PrintDropped(r);
  PrintAnovaTable(r);
  fmt::print(
      "Mauchly p is R's (second-order); nan: the covariance is singular (df > error df),\n"
      "so no test exists; epsilons are still defined. HF eps is uncapped; its p uses min(1, "
      "eps).\n");
  if (between)
    fmt::print(
        "Type 3 sums of squares (sum-to-zero contrasts), as afex; error df {:.0f} = subjects - "
        "between cells.\n",
        r.error_df);
  fmt::print("Significance (--correction {}): ", correction);
  for (std::size_t i = 0; i < r.effects.size(); ++i)
    fmt::print("{}{} p = {:.4g}{}", i ? ", " : "", r.effects[i].effect,
               stats::UsedP(r.effects[i], corr),
               stats::UsedP(r.effects[i], corr) < 0.05 ? " *" : "");
  fmt::print("\n");
  if (!normality.is_null())
    fmt::print("Residuals (afex's residuals()): Shapiro-Wilk W = {:.5f}, p = {:.4g}, n = {}\n",
               normality["W"].get<double>(), normality["p"].get<double>(),
               normality["n"].get<int>());
}

int RunRmAnova(const RmAnovaArgs& o) {
  const auto factors = stats::SplitList(o.within);
  const auto groups = stats::SplitList(o.between);
  if (factors.empty() && groups.empty())
    throw InputError(o.c->csv, 0, "--within", "give --within and/or --between factors");
  std::vector<std::string> keys = factors;
  keys.insert(keys.end(), groups.begin(), groups.end());
  keys.push_back(o.subject);
  const auto data = Load(*o.c, keys);
  const auto corr = stats::ParseCorrection(o.correction, kCommandLine, "--correction");
  stats::RmAnovaResult r;
  Fitted(data, [&] { r = stats::RmAnova(data, o.subject, factors, groups); });
  RequireFinite(data, AnovaValues(r));
  const json normality = ResidualNormality(r);
  if (o.c->json)
    PrintJson(RmAnovaJson(r, corr, o.correction, normality));
  else
    PrintRmAnova(r, !groups.empty(), corr, o.correction, normality);
  return kExitOk;
}

void AddRmAnova(CLI::App& s) {
  auto o = std::make_shared<RmAnovaArgs>();
  auto* cmd = s.add_subcommand(
      "rm-anova",
      "Repeated-measures or mixed ANOVA (within-subject factors, optionally crossed with\n"
      "between-subject factors), as afex::aov_ez with type 3 sums of squares: repetitions\n"
      "averaged per subject x cell, subjects with a missing cell dropped and named. Reports F, p,\n"
      "partial eta squared, and for within terms Mauchly's W and p (R's), Greenhouse-Geisser and\n"
      "Huynh-Feldt epsilons and p.");
  AddCommon(cmd, *o->c);
  AddMissing(cmd, o->c);
  cmd->add_option("--subject", o->subject, "Subject column")->required();
  cmd->add_option("--within", o->within, "Within factors, comma-separated (A or A,B)");
  cmd->add_option(
      "--between", o->between,
      "Between-subject factors, comma-separated (e.g. group): each subject has one level");
  cmd->add_option("--correction", o->correction,
                  "Sphericity correction whose p decides significance (p_used) for within\n"
                  "effects, afex's names: GG (Greenhouse-Geisser, afex's default), HF, none")
      ->check(CLI::IsMember({"GG", "HF", "none"}))
      ->capture_default_str();
  cmd->callback([o] { RunGuarded([&] { return RunRmAnova(*o); }); });
}

// tukey --error: the within-subject error term, pooled (univariate) or per pair.
enum class TukeyError { kUnivariate, kMultivariate };
inline constexpr EnumTable<TukeyError, 2> kTukeyErrorNames{
    {{TukeyError::kUnivariate, "univariate"}, {TukeyError::kMultivariate, "multivariate"}}};

struct TukeyArgs {
  std::shared_ptr<Common> c = std::make_shared<Common>();
  std::string factor, subject, within, between;
  TukeyError error = TukeyError::kUnivariate;
};

// The comparisons: between groups without --subject, else within subjects (the ANOVA's
// error term, a mixed design with --between). `*checked` is the table the fit read.
stats::TukeyResult FitTukey(const TukeyArgs& o, stats::RmAnovaResult* a,
                            stats::LongTable* checked) {
  stats::TukeyResult r;
  if (o.subject.empty()) {
    if (!o.between.empty())
      throw InputError(o.c->csv, 0, "--between", "needs --subject (a mixed design)");
    const auto data = Load(*o.c, {o.factor});
    Fitted(data, [&] { r = stats::TukeyBetween(data, o.factor); });
    *checked = data;
    return r;
  }
  const auto groups = stats::SplitList(o.between);
  const bool factor_between = std::find(groups.begin(), groups.end(), o.factor) != groups.end();
  auto factors = !o.within.empty() ? stats::SplitList(o.within)
                 : factor_between  ? std::vector<std::string>{}
                                   : std::vector<std::string>{o.factor};
  auto keys = factors;
  keys.insert(keys.end(), groups.begin(), groups.end());
  keys.push_back(o.subject);
  const auto data = Load(*o.c, keys);
  Fitted(data, [&] {
    *a = stats::RmAnova(data, o.subject, factors, groups);
    r = stats::TukeyWithin(*a, o.factor, o.error == TukeyError::kMultivariate);
  });
  *checked = data;
  return r;
}

json TukeyJson(const stats::TukeyResult& r, const stats::RmAnovaResult& a) {
  json pairs = json::array();
  for (const auto& p : r.pairs)
    pairs.push_back({{"a", p.a},
                     {"b", p.b},
                     {"diff", p.diff},
                     {"lwr", p.lwr},
                     {"upr", p.upr},
                     {"p_adj", p.p_adj},
                     {"se", p.se},
                     {"df", p.df},
                     {"q", p.q}});
  return json{{"method", r.method},
              {"factor", r.factor},
              {"comparisons", pairs},
              {"dropped_subjects", a.dropped_subjects},
              {"dropped", DroppedJson(a)}};
}

void PrintTukey(const TukeyArgs& o, const stats::TukeyResult& r, const stats::RmAnovaResult& a) {
  if (!o.subject.empty())
    fmt::print("{} subjects{}\n", a.subjects.size(),
               a.dropped_subjects.empty()
                   ? ""
                   : fmt::format(" ({} dropped for a missing cell)", a.dropped_subjects.size()));
  PrintDropped(a);
  fmt::print("Tukey HSD ({}), factor {}, k = {}, df = {:.0f}\n", r.method, r.factor, r.k, r.df);
  fmt::print("{:<30} {:>10} {:>10} {:>10} {:>12}\n", "a - b", "diff", "lwr", "upr", "p adj");
  for (const auto& p : r.pairs)
    fmt::print("{:<30} {:>10.4f} {:>10.4f} {:>10.4f} {:>12.4g}\n", p.a + " - " + p.b, p.diff, p.lwr,
               p.upr, p.p_adj);
}

int RunTukey(const TukeyArgs& o) {
  stats::RmAnovaResult a;
  stats::LongTable checked;
  const stats::TukeyResult r = FitTukey(o, &a, &checked);
  std::vector<std::pair<std::string, double>> values;
  for (const auto& p : r.pairs)
    for (const auto& [n, x] : {std::pair{"diff", p.diff}, std::pair{"lwr", p.lwr},
                               std::pair{"upr", p.upr}, std::pair{"p_adj", p.p_adj},
                               std::pair{"se", p.se}, std::pair{"q", p.q}, std::pair{"df", p.df}})
      values.emplace_back(p.a + " - " + p.b + " " + n, x);
  RequireFinite(checked, values);
  if (o.c->json)
    PrintJson(TukeyJson(r, a));
  else
    PrintTukey(o, r, a);
  return kExitOk;
}

void AddTukey(CLI::App& s) {
  auto o = std::make_shared<TukeyArgs>();
  auto* cmd = s.add_subcommand(
      "tukey",
      "Tukey HSD pairwise comparisons. Without --subject: independent groups (TukeyHSD). With\n"
      "--subject: a within-subject factor, with the pooled error of its effect (--error\n"
      "univariate, emmeans model=\"univariate\") or per-pair errors (--error multivariate, afex's\n"
      "emmeans default). With --between: a mixed design; marginal means average the between\n"
      "cells equally (emmeans). diff = mean(a) - mean(b).");
  AddCommon(cmd, *o->c);
  cmd->add_option("--factor", o->factor, "Factor to compare")->required();
  cmd->add_option("--subject", o->subject, "Subject column (within-subject comparisons)");
  cmd->add_option("--within", o->within, "All within factors of the design (default: --factor)");
  cmd->add_option(
      "--between", o->between,
      "Between-subject factors of a mixed design (with --subject); --factor may be one of them");
  AddMissing(cmd, o->c);
  AddEnumOption(cmd, "--error", o->error, kTukeyErrorNames, "Within-subject error term");
  cmd->callback([o] { RunGuarded([&] { return RunTukey(*o); }); });
}

void AddKruskal(CLI::App& s) {
  auto c = std::make_shared<Common>();
  auto group = std::make_shared<std::string>();
  auto* cmd =
      s.add_subcommand("kruskal",
                       "Kruskal-Wallis with tie correction, then Dunn's test with Bonferroni\n"
                       "adjustment over all pairs. Values are tied when equal to 9 decimals.");
  AddCommon(cmd, *c);
  cmd->add_option("--group", *group, "Grouping column")->required();
  cmd->callback([=] {
    RunGuarded([&] {
      const auto data = Load(*c, {*group});
      stats::KruskalResult k;
      Fitted(data, [&] { k = stats::KruskalWallis(data, *group); });
      std::vector<std::pair<std::string, double>> values{{"H", k.H}, {"p", k.p}};
      for (const auto& d : k.dunn) {
        values.emplace_back(d.a + " vs " + d.b + " z", d.z);
        values.emplace_back(d.a + " vs " + d.b + " p", d.p);
      }
      RequireFinite(data, values);
      if (c->json) {
        json dunn = json::array();
        for (const auto& d : k.dunn)
          dunn.push_back({{"a", d.a}, {"b", d.b}, {"z", d.z}, {"p", d.p}, {"p_adj", d.p_adj}});
        PrintJson(json{{"H", k.H}, {"df", k.df}, {"p", k.p}, {"N", k.N}, {"dunn", dunn}});
        return kExitOk;
      }
      fmt::print("Kruskal-Wallis: H({:.0f}) = {:.4f}, p = {:.4g}, N = {}\n", k.df, k.H, k.p, k.N);
      fmt::print("{:<30} {:>9} {:>11} {:>11}\n", "Dunn a vs b", "z", "p", "p (Bonf.)");
      for (const auto& d : k.dunn)
        fmt::print("{:<30} {:>9.4f} {:>11.4g} {:>11.4g}\n", d.a + " vs " + d.b, d.z, d.p, d.p_adj);
      return kExitOk;
    });
  });
}

void AddShapiro(CLI::App& s) {
  auto c = std::make_shared<Common>();
  auto by = std::make_shared<std::string>();
  auto* cmd = s.add_subcommand(
      "shapiro", "Shapiro-Wilk normality test (Royston's AS R94, as R), overall or per group");
  AddCommon(cmd, *c);
  cmd->add_option("--by", *by, "Test each group of this column separately");
  cmd->callback([=] {
    RunGuarded([&] {
      const auto t =
          Load(*c, by->empty() ? std::vector<std::string>{} : std::vector<std::string>{*by});
      json groups = json::array();
      auto one = [&](const std::string& name, const std::vector<double>& y) {
        stats::ShapiroResult r;
        Fitted(t, [&] {
          try {
            r = stats::ShapiroWilk(y);
          } catch (const InputError& e) {  // too few or many values, no spread
            throw InputError(t.source, 0, c->dv,
                             "group " + name + ": " + e.diagnostics().front().message);
          }
        });
        RequireFinite(t, {{name + " W", r.W}, {name + " p", r.p}});
        groups.push_back({{"group", name}, {"n", r.n}, {"W", r.W}, {"p", r.p}});
      };
      if (by->empty())
        one("all", t.y);
      else
        for (const auto& g : t.Levels(*by)) one(g, t.Where({{*by, g}}).y);
      if (c->json) {
        PrintJson(json{{"groups", groups}});
      } else {
        for (const auto& g : groups)
          fmt::print("{:<24} n = {:>5}  W = {:.5f}  p = {:.4g}\n", g["group"].get<std::string>(),
                     g["n"].get<int>(), g["W"].get<double>(), g["p"].get<double>());
      }
      return kExitOk;
    });
  });
}

}  // namespace

void AddStatsCommands(CLI::App& group, const PsychometricFigure& draw) {
  AddRmAnova(group);
  AddTukey(group);
  AddKruskal(group);
  AddShapiro(group);
  stats_cmd::AddLmm(group);
  stats_cmd::AddPsychometric(group, draw);
}

void AddStatsCommands(CLI::App& group) { AddStatsCommands(group, {}); }

void RegisterStats(CLI::App& app) { RegisterStats(app, {}); }

void RegisterStats(CLI::App& app, const PsychometricFigure& draw) {
  auto* s = app.add_subcommand(
      "stats",
      "Statistics on any long-format CSV (see docs/analysis.md):\n"
      "rm-anova, tukey, kruskal, shapiro, lmm, psychometric. The same commands, with a fast\n"
      "start (no GUI, device or modeling libraries loaded): hapticlab-stats COMMAND");
  s->require_subcommand(1);
  AddStatsCommands(*s, draw);
}

}  // namespace hapticlab::cli
