// hapticlab stats psychometric: ML psychometric fits of binomial data in any CSV, with the fit
// and bootstrap of the adaptive phases (stats/psychometric_csv.hpp, docs/psychophysics.md).

#include <fmt/core.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "cmd_stats_common.hpp"
#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/stats/psychometric_csv.hpp"
#include "hapticlab/stats/psychometric_report.hpp"

namespace hapticlab::cli::stats_cmd {
namespace {

using nlohmann::json;

struct PsyOpts {
  std::string csv, link = "logit", by, figure;
  stats::PsychometricColumns columns;
  std::vector<double> performances;
  bool lapse = false, json = false;
  double max_lapse = 0.06, jnd_at = 0.75, reference = 0, ci = 0.95;
  int replicates = 1000;
  std::uint64_t seed = 1;
};

json Interval(double value, const stats::BootstrapInterval& ci) {
  return json{{"value", Num(value)}, {"lo", Num(ci.lo)}, {"hi", Num(ci.hi)}};
}

std::string Text(double value, const stats::BootstrapInterval& ci) {
  std::string v = std::isfinite(value) ? fmt::format("{:.6g}", value) : "n/a";
  if (!std::isfinite(ci.lo) && !std::isfinite(ci.hi)) return v;
  return fmt::format("{} [{:.6g}, {:.6g}]", v, ci.lo, ci.hi);
}

// Where F(alpha) lies: 0.5 for logit and probit, 1 - 1/e for the Weibull.
double CoreAtThreshold(psychophysics::Shape s) {
  return s == psychophysics::Shape::kWeibull ? 1 - std::exp(-1.0) : 0.5;
}

json GroupJson(const stats::PsychometricGroup& g, const stats::PsychometricSummary& s,
               const PsyOpts& o, const std::vector<std::string>& figure) {
  json keys = json::object();
  for (const auto& [col, val] : g.keys) keys[col] = val;
  const auto& f = s.fit;
  const int params = 2 + (o.lapse ? 1 : 0);
  json j{{"group", keys},      {"name", g.Name()},          {"rows", g.data.x.size()},
         {"trials", s.trials}, {"usable", f.usable},        {"message", f.message},
         {"figure", figure},   {"iterations", f.iterations}};
  if (!f.usable) return j;
  json at = json::array();
  for (std::size_t i = 0; i < o.performances.size(); ++i) {
    json a = Interval(s.stimulus_at[i], s.boot.stimulus_at[i]);
    a["performance"] = o.performances[i];
    at.push_back(a);
  }
  j.update(json{{"a", f.a},
                {"b", f.b},
                {"se_a", Num(f.se_a)},
                {"se_b", Num(f.se_b)},
                {"deviance", f.deviance},
                {"df_residual", static_cast<int>(g.data.x.size()) - params},
                {"log_likelihood", f.log_likelihood},
                {"guess", f.params.guess},
                {"lapse", f.params.lapse},
                {"threshold", Interval(f.params.threshold, s.boot.threshold)},
                {"slope", Interval(f.params.slope, s.boot.slope)},
                {"stimulus_at", at},
                {"jnd", Interval(s.jnd, s.boot.jnd)},
                {"weber_fraction", Interval(s.weber, s.weber_ci)},
                {"bootstrap_replicates", s.boot.replicates},
                {"bootstrap_failed", s.boot.failed}});
  return j;
}

void PrintGroup(const stats::PsychometricGroup& g, const stats::PsychometricSummary& s,
                const PsyOpts& o, psychophysics::Shape shape) {
  const auto& f = s.fit;
  fmt::print("{}: {} rows, {} trials\n", g.Name(), g.data.x.size(), s.trials);
  if (!f.usable) {
    fmt::print("  fit not usable: {}\n", f.message);
    return;
  }
  const int params = 2 + (o.lapse ? 1 : 0);
  fmt::print("  eta = a + b {}: a = {:.8g} (SE {:.4g}), b = {:.8g} (SE {:.4g})\n",
             shape == psychophysics::Shape::kWeibull ? "ln(x)" : "x", f.a, f.se_a, f.b, f.se_b);
  fmt::print("  deviance {:.8g} on {} df, log-likelihood {:.8g}, lapse {:.4g}\n", f.deviance,
             static_cast<int>(g.data.x.size()) - params, f.log_likelihood, f.params.lapse);
  fmt::print("  threshold (F = {:.3g}) {}\n  slope {}\n", CoreAtThreshold(shape),
             Text(f.params.threshold, s.boot.threshold), Text(f.params.slope, s.boot.slope));
  for (std::size_t i = 0; i < o.performances.size(); ++i)
    fmt::print("  x at {:.4g} % {}\n", 100 * o.performances[i],
               Text(s.stimulus_at[i], s.boot.stimulus_at[i]));
  fmt::print("  JND (x at {:.4g} %) {}\n", 100 * o.jnd_at, Text(s.jnd, s.boot.jnd));
  if (o.reference > 0)
    fmt::print("  Weber fraction (JND / {:.6g}) {}\n", o.reference, Text(s.weber, s.weber_ci));
  if (s.boot.failed > 0)
    fmt::print("  ({} of the bootstrap refits did not converge and were left out)\n",
               s.boot.failed);
}

// Checks the options against the link; returns the summary options.
stats::PsychometricSummaryOptions Prepare(const PsyOpts& o, const stats::PsychometricLink& link) {
  stats::PsychometricSummaryOptions s;
  s.fit.shape = link.shape;
  s.fit.guess = link.guess;
  s.fit.lapse_free = o.lapse;
  s.fit.max_lapse = o.max_lapse;
  if (o.lapse && !(o.max_lapse > 0 && o.max_lapse < 1 - link.guess))
    throw InputError(kCommandLine, 0, "--max-lapse",
                     fmt::format("expected a value in (0, {:.4g}) for this link", 1 - link.guess));
  for (const double p : o.performances)
    if (!(p > link.guess && p < 1))
      throw InputError(
          kCommandLine, 0, "--performance",
          fmt::format("{} is outside ({:.4g}, 1), the range of link {}", p, link.guess, link.name));
  if (!(o.jnd_at > link.guess && o.jnd_at < 1))
    throw InputError(kCommandLine, 0, "--jnd-at",
                     fmt::format("{} is outside ({:.4g}, 1), the range of link {}", o.jnd_at,
                                 link.guess, link.name));
  s.performances = o.performances;
  s.jnd_performance = o.jnd_at;
  s.reference = o.reference;
  s.replicates = o.replicates;
  s.seed = o.seed;
  s.level = o.ci;
  return s;
}

std::string FigureBase(const std::string& prefix, const stats::PsychometricGroup& g, bool one) {
  if (one) return prefix;
  std::string s;
  for (char c : g.Name()) s += std::isalnum(static_cast<unsigned char>(c)) || c == '.' ? c : '_';
  return prefix + "_" + s;
}

int Run(const PsyOpts& o, const PsychometricFigure& draw) {
  std::string why;
  const auto link = stats::ParsePsychometricLink(o.link, &why);
  if (!link) throw InputError(kCommandLine, 0, "--link", why);
  if (!o.figure.empty() && !draw)
    throw InputError(kCommandLine, 0, "--figure",
                     "hapticlab-stats draws no figures (it loads no plotting library): run "
                     "'hapticlab stats psychometric' with the same options");
  if (o.columns.trials.empty() == o.columns.incorrect.empty())
    throw InputError(kCommandLine, 0, "--trials",
                     "give exactly one of --trials (the trials per row) and --incorrect");
  const auto options = Prepare(o, *link);
  auto columns = o.columns;
  columns.by = stats::SplitList(o.by);
  const auto groups =
      stats::ReadPsychometricCsv(o.csv, columns, link->shape == psychophysics::Shape::kWeibull);
  json out = json::array();
  int usable = 0;
  std::uint64_t seed = o.seed;
  for (const auto& g : groups) {
    auto opts = options;
    opts.seed = seed++;  // each group its own stream, reproducible for --seed
    const auto s = stats::SummarizePsychometric(g.data, opts);
    usable += s.fit.usable ? 1 : 0;
    std::vector<std::string> files;
    if (s.fit.usable && !o.figure.empty()) {
      stats::PsychometricPlot plot;
      plot.title = fmt::format("{} ({})", g.Name(), link->name);
      plot.x_label = o.columns.level;
      plot.binned = stats::BinForPlot(g.data);
      plot.shape = link->shape;
      plot.fit = s.fit.params;
      plot.jnd = s.jnd;
      plot.jnd_performance = o.jnd_at;
      files = draw(plot, FigureBase(o.figure, g, groups.size() == 1));
    }
    if (o.json)
      out.push_back(GroupJson(g, s, o, files));
    else
      PrintGroup(g, s, o, link->shape);
    for (const auto& f : files)
      if (!o.json) fmt::print("  figure: {}\n", f);
  }
  if (o.json)
    PrintJson(json{{"csv", o.csv},
                   {"link", link->name},
                   {"guess", link->guess},
                   {"lapse", o.lapse ? "free" : "fixed at 0"},
                   {"jnd_performance", o.jnd_at},
                   {"reference", Num(o.reference > 0 ? o.reference : NAN)},
                   {"bootstrap", {{"replicates", o.replicates}, {"seed", o.seed}, {"level", o.ci}}},
                   {"groups", out}});
  if (usable == 0)
    throw InputError(o.csv, 0, o.columns.correct,
                     "no group could be fitted (see the message of each group above)");
  return kExitOk;
}

}  // namespace

void AddPsychometric(CLI::App& s, PsychometricFigure draw) {
  auto o = std::make_shared<PsyOpts>();
  auto* cmd = s.add_subcommand(
      "psychometric",
      "Maximum-likelihood psychometric fits of binomial data (one row: a stimulus level, the\n"
      "correct or 'yes' count and the trials), as R's glm(binomial) with psyphy's mafc links;\n"
      "percentile intervals from a parametric bootstrap; the stimulus at chosen performances,\n"
      "the JND and the Weber fraction. The same fit as analyze's adaptive phases\n"
      "(docs/psychophysics.md).");
  cmd->add_option("--csv", o->csv, "CSV with one row per stimulus level (and group)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--level", o->columns.level, "Column of the stimulus level x")->required();
  cmd->add_option("--correct", o->columns.correct, "Column of the correct (or 'yes') counts")
      ->required();
  cmd->add_option("--trials", o->columns.trials, "Column of the trial counts");
  cmd->add_option("--incorrect", o->columns.incorrect,
                  "Column of the incorrect counts (instead of --trials; R's cbind(k, n - k))");
  cmd->add_option("--by", o->by, "Fit each combination of these columns separately (A or A,B)");
  cmd->add_option("--link", o->link,
                  "logit, probit, weibull (guess rate 0; weibull fits ln x), or\n"
                  "mafc-logit:m, mafc-probit:m, mafc-weibull:m (m-alternative forced choice,\n"
                  "guess rate 1/m; psyphy's mafc.logit, mafc.probit, mafc.cloglog)")
      ->capture_default_str();
  cmd->add_flag("--lapse", o->lapse, "Fit the lapse rate too (in [0, --max-lapse]; else 0)");
  cmd->add_option("--max-lapse", o->max_lapse, "Upper bound of a free lapse rate")
      ->capture_default_str();
  cmd->add_option("--performance", o->performances,
                  "Report the stimulus at these performances (proportions, e.g. 0.5,0.75)")
      ->delimiter(',');
  cmd->add_option("--jnd-at", o->jnd_at,
                  "JND = the level at this performance (x as a difference from the reference)")
      ->capture_default_str();
  cmd->add_option("--reference", o->reference,
                  "Reference stimulus (> 0, the level's unit): Weber fraction = JND / reference")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--bootstrap", o->replicates, "Parametric-bootstrap refits (0: no intervals)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the bootstrap")->capture_default_str();
  cmd->add_option("--ci", o->ci, "Level of the intervals")
      ->check(CLI::Range(0.5, 0.999))
      ->capture_default_str();
  cmd->add_option("--figure", o->figure,
                  "Write PREFIX.svg and PREFIX.png (PREFIX_<group>.* with --by): the fit over\n"
                  "the data, JND marked (hapticlab only; hapticlab-stats draws none)");
  cmd->add_flag("--json", o->json, "Print results as JSON");
  cmd->callback([o, draw] {
    RunGuarded({{"trials", "--trials"}}, [&] {
      if (o->replicates == 1)
        throw InputError(kCommandLine, 0, "--bootstrap", "expected 0 or at least 2 refits");
      return Run(*o, draw);
    });
  });
}

}  // namespace hapticlab::cli::stats_cmd
