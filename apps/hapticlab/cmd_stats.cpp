// hapticlab stats: the statistics on any long-format CSV, without a study database.

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "hapticlab/core/csv.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/anova.hpp"
#include "hapticlab/stats/lmm.hpp"
#include "hapticlab/stats/nonparametric.hpp"
#include "hapticlab/stats/shapiro.hpp"
#include "hapticlab/stats/tukey.hpp"

namespace hapticlab::cli {
namespace {

using nlohmann::json;

// NaN (undefined statistics) becomes JSON null.
json Num(double v) { return std::isfinite(v) ? json(v) : json(); }

// Options every stats subcommand shares.
struct Common {
  std::string csv, dv;
  std::vector<std::string> where;  // COL=VALUE
  std::string average_by;          // COLS
  bool json = false;
  bool allow_missing = false;      // rm-anova/tukey --within: --missing drop-subject
  bool include_simulated = false;  // keep source=simulated rows next to a person's ratings
};

void AddCommon(CLI::App* cmd, Common& c) {
  cmd->add_option("--csv", c.csv, "Long-format CSV (one row per observation)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--dv", c.dv, "Column of the response (numeric)")->required();
  cmd->add_option("--where", c.where,
                  "Keep rows with COL=VALUE (repeatable), e.g. --where criterion=roughness");
  cmd->add_option("--average-by", c.average_by,
                  "Average the response within each combination of these columns first, e.g.\n"
                  "subject,method,material to use cell means (repetitions averaged)");
  cmd->add_flag("--json", c.json, "Print results as JSON");
  cmd->add_flag(
      "--include-simulated", c.include_simulated,
      "A CSV with a 'source' column (hapticlab export): keep the simulated observer's rows\n"
      "although rows rated by participants are present (left out by default, with a note)");
}

// Reads the CSV with the needed key columns, applies --where and --average-by.
stats::LongTable Load(const Common& c, std::vector<std::string> keys) {
  std::vector<std::pair<std::string, std::string>> cond;
  for (const auto& w : c.where) {
    const auto eq = w.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError(kCommandLine, 0, "--where", "expected COL=VALUE, got '" + w + "'");
    cond.emplace_back(w.substr(0, eq), w.substr(eq + 1));
    keys.push_back(cond.back().first);
  }
  const auto avg = stats::SplitList(c.average_by);
  keys.insert(keys.end(), avg.begin(), avg.end());
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  stats::RowFilter keep{.equal = cond, .not_equal = {}};
  // The project's exports carry each rating's source: when a person rated any row, the
  // simulated observer's rows are left out unless asked for (docs/analysis.md).
  {
    const CsvTable raw = ReadCsv(c.csv);
    if (const auto sc = raw.Find("source"); sc && !c.include_simulated) {
      std::size_t simulated = 0, human = 0;
      for (const auto& row : raw.rows)
        (row[*sc] == "simulated" ? simulated : human) += row[*sc].empty() ? 0 : 1;
      if (simulated && human) {
        keep.not_equal.emplace_back("source", "simulated");
        fmt::print(stderr,
                   "note: {}: {} rows rated by the simulated observer are left out ({} rated by "
                   "participants); "
                   "--include-simulated keeps them\n",
                   c.csv, simulated, human);
      }
    }
  }
  auto t = stats::ReadLongCsv(c.csv, c.dv, keys, c.allow_missing, keep);
  if (t.rows() == 0) throw InputError(c.csv, 0, "--where", "no rows left after filtering");
  if (!avg.empty()) t = t.Average(avg);
  return t;
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

void AddRmAnova(CLI::App& s) {
  auto c = std::make_shared<Common>();
  auto subject = std::make_shared<std::string>();
  auto within = std::make_shared<std::string>();
  auto between = std::make_shared<std::string>();
  auto* cmd = s.add_subcommand(
      "rm-anova",
      "Repeated-measures or mixed ANOVA (within-subject factors, optionally crossed with\n"
      "between-subject factors), as afex::aov_ez with type 3 sums of squares: repetitions\n"
      "averaged per subject x cell, subjects with a missing cell dropped and named. Reports F, p,\n"
      "partial eta squared, and for within terms Mauchly's W and p (R's), Greenhouse-Geisser and\n"
      "Huynh-Feldt epsilons and p.");
  AddCommon(cmd, *c);
  AddMissing(cmd, c);
  cmd->add_option("--subject", *subject, "Subject column")->required();
  cmd->add_option("--within", *within, "Within factors, comma-separated (A or A,B)");
  cmd->add_option(
      "--between", *between,
      "Between-subject factors, comma-separated (e.g. group): each subject has one level");
  cmd->callback([=] {
    RunGuarded([&] {
      const auto factors = stats::SplitList(*within);
      const auto groups = stats::SplitList(*between);
      if (factors.empty() && groups.empty())
        throw InputError(c->csv, 0, "--within", "give --within and/or --between factors");
      std::vector<std::string> keys = factors;
      keys.insert(keys.end(), groups.begin(), groups.end());
      keys.push_back(*subject);
      const auto r = stats::RmAnova(Load(*c, keys), *subject, factors, groups);
      if (c->json) {
        json effects = json::array();
        for (const auto& e : r.effects)
          effects.push_back({{"effect", e.effect},
                             {"df1", e.df1},
                             {"df2", e.df2},
                             {"F", e.F},
                             {"p", e.p},
                             {"pes", e.pes},
                             {"SS", e.SS},
                             {"SS_error", e.SS_error},
                             {"MSE", e.MSE},
                             {"mauchly_W", Num(e.mauchly_W)},
                             {"mauchly_p", Num(e.mauchly_p)},
                             {"mauchly_p_firstorder", Num(e.mauchly_p_firstorder)},
                             {"gg_epsilon", Num(e.gg_epsilon)},
                             {"p_gg", Num(e.p_gg)},
                             {"hf_epsilon", Num(e.hf_epsilon)},
                             {"p_hf", Num(e.p_hf)},
                             {"between_only", e.between_only}});
        PrintJson(json{{"effects", effects},
                       {"subjects", r.subjects.size()},
                       {"dropped_subjects", r.dropped_subjects},
                       {"dropped", DroppedJson(r)}});
        return kExitOk;
      }
      fmt::print("{} subjects{}\n", r.subjects.size(),
                 r.dropped_subjects.empty()
                     ? ""
                     : fmt::format(" ({} dropped for a missing cell)", r.dropped_subjects.size()));
      PrintDropped(r);
      fmt::print("{:<24} {:>5} {:>7} {:>10} {:>11} {:>7} {:>9} {:>9} {:>7} {:>10} {:>7} {:>10}\n",
                 "effect", "df1", "df2", "F", "p", "pes", "Mauchly W", "p", "GG eps", "p GG",
                 "HF eps", "p HF");
      for (const auto& e : r.effects) {
        if (e.between_only) {  // between-subjects term: no sphericity question
          fmt::print("{:<24} {:>5.0f} {:>7.0f} {:>10.4f} {:>11.4g} {:>7.3f}\n", e.effect, e.df1,
                     e.df2, e.F, e.p, e.pes);
          continue;
        }
        fmt::print(
            "{:<24} {:>5.0f} {:>7.0f} {:>10.4f} {:>11.4g} {:>7.3f} {:>9.4g} {:>9.4g} {:>7.4f} "
            "{:>10.4g} {:>7.4f} {:>10.4g}\n",
            e.effect, e.df1, e.df2, e.F, e.p, e.pes, e.mauchly_W, e.mauchly_p, e.gg_epsilon, e.p_gg,
            e.hf_epsilon, e.p_hf);
      }
      fmt::print(
          "Mauchly p is R's (second-order); nan: the covariance is singular (df > error df),\n"
          "so no test exists; epsilons are still defined. HF eps is uncapped; its p uses min(1, "
          "eps).\n");
      if (!groups.empty())
        fmt::print(
            "Type 3 sums of squares (sum-to-zero contrasts), as afex; error df {:.0f} = subjects - "
            "between cells.\n",
            r.error_df);
      return kExitOk;
    });
  });
}

void AddTukey(CLI::App& s) {
  auto c = std::make_shared<Common>();
  auto factor = std::make_shared<std::string>();
  auto subject = std::make_shared<std::string>();
  auto within = std::make_shared<std::string>();
  auto method = std::make_shared<std::string>("univariate");
  auto* cmd = s.add_subcommand(
      "tukey",
      "Tukey HSD pairwise comparisons. Without --subject: independent groups (TukeyHSD). With\n"
      "--subject: a within-subject factor, with the pooled error of its effect (--error\n"
      "univariate, emmeans model=\"univariate\") or per-pair errors (--error multivariate, afex's\n"
      "emmeans default). With --between: a mixed design; marginal means average the between\n"
      "cells equally (emmeans). diff = mean(a) - mean(b).");
  AddCommon(cmd, *c);
  cmd->add_option("--factor", *factor, "Factor to compare")->required();
  cmd->add_option("--subject", *subject, "Subject column (within-subject comparisons)");
  cmd->add_option("--within", *within, "All within factors of the design (default: --factor)");
  auto between = std::make_shared<std::string>();
  cmd->add_option(
      "--between", *between,
      "Between-subject factors of a mixed design (with --subject); --factor may be one of them");
  AddMissing(cmd, c);
  cmd->add_option("--error", *method, "Within-subject error term")
      ->check(CLI::IsMember({"univariate", "multivariate"}))
      ->capture_default_str();
  cmd->callback([=] {
    RunGuarded([&] {
      stats::TukeyResult r;
      stats::RmAnovaResult a;
      if (subject->empty()) {
        if (!between->empty())
          throw InputError(c->csv, 0, "--between", "needs --subject (a mixed design)");
        r = stats::TukeyBetween(Load(*c, {*factor}), *factor);
      } else {
        const auto groups = stats::SplitList(*between);
        const bool factor_between =
            std::find(groups.begin(), groups.end(), *factor) != groups.end();
        auto factors = !within->empty() ? stats::SplitList(*within)
                       : factor_between ? std::vector<std::string>{}
                                        : std::vector<std::string>{*factor};
        auto keys = factors;
        keys.insert(keys.end(), groups.begin(), groups.end());
        keys.push_back(*subject);
        a = stats::RmAnova(Load(*c, keys), *subject, factors, groups);
        r = stats::TukeyWithin(a, *factor, *method == "multivariate");
      }
      if (c->json) {
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
        PrintJson(json{{"method", r.method},
                       {"factor", r.factor},
                       {"comparisons", pairs},
                       {"dropped_subjects", a.dropped_subjects},
                       {"dropped", DroppedJson(a)}});
        return kExitOk;
      }
      if (!subject->empty())
        fmt::print("{} subjects{}\n", a.subjects.size(),
                   a.dropped_subjects.empty() ? ""
                                              : fmt::format(" ({} dropped for a missing cell)",
                                                            a.dropped_subjects.size()));
      PrintDropped(a);
      fmt::print("Tukey HSD ({}), factor {}, k = {}, df = {:.0f}\n", r.method, r.factor, r.k, r.df);
      fmt::print("{:<30} {:>10} {:>10} {:>10} {:>12}\n", "a - b", "diff", "lwr", "upr", "p adj");
      for (const auto& p : r.pairs)
        fmt::print("{:<30} {:>10.4f} {:>10.4f} {:>10.4f} {:>12.4g}\n", p.a + " - " + p.b, p.diff,
                   p.lwr, p.upr, p.p_adj);
      return kExitOk;
    });
  });
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
      const auto k = stats::KruskalWallis(Load(*c, {*group}), *group);
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
        const auto r = stats::ShapiroWilk(y);
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

json LmmJson(const stats::LmmResult& r) {
  json fixed = json::array(), anova = json::array(), random = json::array();
  for (const auto& c : r.fixed)
    fixed.push_back({{"name", c.name},
                     {"estimate", c.estimate},
                     {"se", c.se},
                     {"df", Num(c.df)},
                     {"t", c.t},
                     {"p", Num(c.p)}});
  for (const auto& t : r.anova)
    anova.push_back({{"term", t.term},
                     {"num_df", t.num_df},
                     {"den_df", Num(t.den_df)},
                     {"F", t.F},
                     {"p", Num(t.p)}});
  for (const auto& g : r.random) {
    json corr = json::array();
    for (const auto& row : g.corr) {
      json jr = json::array();
      for (double v : row) jr.push_back(Num(v));
      corr.push_back(jr);
    }
    random.push_back({{"group", g.group},
                      {"levels", g.levels},
                      {"names", g.names},
                      {"variance", g.variance},
                      {"sd", g.sd},
                      {"corr", corr}});
  }
  return json{{"formula", r.formula},
              {"method", r.reml ? "REML" : "ML"},
              {"n", r.n},
              {"fixed", fixed},
              {"anova_type3", anova},
              {"ddf", r.ddf},
              {"random", random},
              {"residual_variance", r.sigma * r.sigma},
              {"sigma", r.sigma},
              {"theta", r.theta},
              {r.reml ? "REML_criterion" : "deviance", r.deviance},
              {"logLik", r.logLik},
              {"AIC", r.AIC},
              {"BIC", r.BIC},
              {"n_parameters", r.n_parameters},
              {"convergence",
               {{"optimizer", r.optimizer},
                {"converged", r.converged},
                {"evaluations", r.evaluations},
                {"gradient_max_abs", r.gradient_max_abs},
                {"singular", r.singular}}}};
}

void PrintLmm(const stats::LmmResult& r) {
  fmt::print("Linear mixed model fit by {} (lme4's formulation), {} observations\nFormula: {}\n",
             r.reml ? "REML" : "maximum likelihood", r.n, r.formula);
  fmt::print("{} {:.4f}   logLik {:.4f}   AIC {:.4f}   BIC {:.4f}   ({} parameters)\n\n",
             r.reml ? "REML criterion" : "deviance", r.deviance, r.logLik, r.AIC, r.BIC,
             r.n_parameters);
  fmt::print("Random effects:\n{:<16} {:<22} {:>12} {:>10}  {}\n", "group (levels)", "name",
             "variance", "SD", "corr");
  for (const auto& g : r.random)
    for (std::size_t i = 0; i < g.names.size(); ++i) {
      std::string corr;
      for (std::size_t j = 0; j < i; ++j) corr += fmt::format("{:>7.3f}", g.corr[i][j]);
      fmt::print("{:<16} {:<22} {:>12.5g} {:>10.5g}  {}\n",
                 i == 0 ? fmt::format("{} ({})", g.group, g.levels) : "", g.names[i], g.variance[i],
                 g.sd[i], corr);
    }
  fmt::print("{:<16} {:<22} {:>12.5g} {:>10.5g}\n\n", "Residual", "", r.sigma * r.sigma, r.sigma);
  fmt::print(
      "Fixed effects (sum-to-zero contrasts; {} df):\n{:<28} {:>12} {:>10} {:>9} {:>9} {:>11}\n",
      r.ddf, "name", "estimate", "SE", "df", "t", "p");
  for (const auto& c : r.fixed)
    fmt::print("{:<28} {:>12.5g} {:>10.4g} {:>9.2f} {:>9.3f} {:>11.4g}\n", c.name, c.estimate, c.se,
               c.df, c.t, c.p);
  fmt::print(
      "\nType III F tests ({} df, as lmerTest anova(m, type = 3) / afex::mixed):\n"
      "{:<28} {:>6} {:>9} {:>10} {:>11}\n",
      r.ddf, "term", "num df", "den df", "F", "p");
  for (const auto& t : r.anova)
    fmt::print("{:<28} {:>6.0f} {:>9.2f} {:>10.4f} {:>11.4g}\n", t.term, t.num_df, t.den_df, t.F,
               t.p);
  fmt::print(
      "\nConvergence: {}; {} after {} deviance evaluations; max |d deviance / d theta| = "
      "{:.2g}{}\n",
      r.optimizer, r.converged ? "converged" : "NOT converged", r.evaluations, r.gradient_max_abs,
      r.singular
          ? "\nboundary (singular) fit: a variance is 0 or a correlation is +-1 (lme4's isSingular)"
          : "");
}

void AddLmm(CLI::App& s) {
  auto c = std::make_shared<Common>();
  auto formula = std::make_shared<std::string>();
  auto ml = std::make_shared<bool>(false);
  auto ddf = std::make_shared<std::string>("satterthwaite");
  auto* cmd = s.add_subcommand(
      "lmm",
      "Linear mixed model, fitted as lme4::lmer (penalised least squares, sparse Cholesky,\n"
      "profiled REML or ML deviance), with lmerTest's Satterthwaite df for the coefficient t "
      "tests\n"
      "and the type 3 F tests (sum-to-zero contrasts, as afex::mixed method \"S\"). Reports the\n"
      "random-effect variances, SDs and correlations, logLik/AIC/BIC and convergence diagnostics.\n"
      "Numeric columns are covariates, text columns factors (as read.csv). Every row is one\n"
      "observation (no averaging).");
  cmd->add_option("--csv", c->csv, "Long-format CSV (one row per observation)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--formula", *formula,
                  "lme4 formula, e.g. 'score ~ method * texture + (1 + method | participant) + (1 "
                  "| material)'")
      ->required();
  cmd->add_option("--where", c->where,
                  "Keep rows with COL=VALUE (repeatable), e.g. --where criterion=roughness");
  auto reml = std::make_shared<bool>(false);
  auto* reml_flag =
      cmd->add_flag("--reml", *reml, "Restricted maximum likelihood (the default, as lmer)");
  cmd->add_flag("--ml", *ml, "Maximum likelihood (for comparing fixed effects by likelihood ratio)")
      ->excludes(reml_flag);
  cmd->add_option(
         "--ddf", *ddf,
         "Denominator df of the t and F tests: satterthwaite (lmerTest's default) or "
         "kenward-roger\n"
         "(pbkrtest's adjusted SEs and scaled F, as lmerTest ddf = \"Kenward-Roger\"; REML only)")
      ->check(CLI::IsMember({"satterthwaite", "kenward-roger"}))
      ->capture_default_str();
  cmd->add_flag("--json", c->json, "Print results as JSON");
  cmd->callback([=] {
    RunGuarded([&] {
      // The library names the fields "formula" and "ddf"; the user set them with these flags.
      WithFlags({{"formula", "--formula"}, {"ddf", "--ddf"}}, [&] {
        const auto f = stats::ParseLmmFormula(*formula, c->csv);
        c->dv = f.response;
        auto keys = f.Columns();
        keys.erase(keys.begin());
        stats::LmmOptions o;
        o.reml = !*ml;
        o.kenward_roger = *ddf == "kenward-roger";
        const auto r = stats::FitLmm(Load(*c, keys), *formula, o);
        if (c->json)
          PrintJson(LmmJson(r));
        else
          PrintLmm(r);
      });
      return kExitOk;
    });
  });
}

}  // namespace

void AddStatsCommands(CLI::App& group) {
  AddRmAnova(group);
  AddTukey(group);
  AddKruskal(group);
  AddShapiro(group);
  AddLmm(group);
}

void RegisterStats(CLI::App& app) {
  auto* s = app.add_subcommand(
      "stats",
      "Statistics on any long-format CSV (see docs/analysis.md):\n"
      "rm-anova, tukey, kruskal, shapiro, lmm. The same commands, with a fast start\n"
      "(no GUI, device or modeling libraries loaded): hapticlab-stats COMMAND");
  s->require_subcommand(1);
  AddStatsCommands(*s);
}

}  // namespace hapticlab::cli
