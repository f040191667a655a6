// hapticlab stats lmm: linear mixed models (lme4's formulation, lmerTest's tests).

#include <fmt/core.h>

#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "cmd_stats_common.hpp"
#include "hapticlab/stats/lmm.hpp"

namespace hapticlab::cli::stats_cmd {
namespace {

using nlohmann::json;

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
      "Fixed effects (factors coded as R does with contr.sum; {} df):\n{:<28} {:>12} {:>10} {:>9} "
      "{:>9} {:>11}\n",
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

// lmm --ddf: the denominator df of the t and F tests.
enum class Ddf { kSatterthwaite, kKenwardRoger };
inline constexpr EnumTable<Ddf, 2> kDdfNames{
    {{Ddf::kSatterthwaite, "satterthwaite"}, {Ddf::kKenwardRoger, "kenward-roger"}}};

}  // namespace

void AddLmm(CLI::App& s) {
  auto c = std::make_shared<Common>();
  auto formula = std::make_shared<std::string>();
  auto ml = std::make_shared<bool>(false);
  auto ddf = std::make_shared<Ddf>(Ddf::kSatterthwaite);
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
                  "| material)'; also (x || g), (1 | a/b), (1 | a:b), 0 + x, x - 1, and log, exp, "
                  "sqrt, scale, I() of the response and numeric columns (docs/analysis.md)")
      ->required();
  cmd->add_option("--where", c->where,
                  "Keep rows with COL=VALUE (repeatable), e.g. --where criterion=roughness");
  auto reml = std::make_shared<bool>(false);
  auto* reml_flag =
      cmd->add_flag("--reml", *reml, "Restricted maximum likelihood (the default, as lmer)");
  cmd->add_flag("--ml", *ml, "Maximum likelihood (for comparing fixed effects by likelihood ratio)")
      ->excludes(reml_flag);
  AddEnumOption(
      cmd, "--ddf", *ddf, kDdfNames,
      "Denominator df of the t and F tests: satterthwaite (lmerTest's default) or "
      "kenward-roger\n"
      "(pbkrtest's adjusted SEs and scaled F, as lmerTest ddf = \"Kenward-Roger\"; REML only)");
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
        o.kenward_roger = *ddf == Ddf::kKenwardRoger;
        const auto data = Load(*c, keys);
        stats::LmmResult r;
        Fitted(data, [&] { r = stats::FitLmm(data, *formula, o); });
        std::vector<std::pair<std::string, double>> values{
            {"sigma", r.sigma}, {"logLik", r.logLik}, {"deviance", r.deviance}};
        for (const auto& b : r.fixed)
          for (const auto& [n, x] :
               {std::pair{"estimate", b.estimate}, std::pair{"se", b.se}, std::pair{"t", b.t}})
            values.emplace_back(b.name + " " + n, x);
        for (const auto& t : r.anova) values.emplace_back(t.term + " F", t.F);
        for (const auto& g : r.random)
          for (std::size_t i = 0; i < g.sd.size(); ++i)
            values.emplace_back(g.group + " " + g.names[i] + " SD", g.sd[i]);
        RequireFinite(data, values);
        if (c->json)
          PrintJson(LmmJson(r));
        else
          PrintLmm(r);
      });
      return kExitOk;
    });
  });
}

}  // namespace hapticlab::cli::stats_cmd
