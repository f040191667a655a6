// hapticlab fit: fit a model's effects to a measurement (docs/workbench.md).

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>

#include "cli_common.hpp"
#include "commands.hpp"
#include "fit_summary_json.hpp"
#include "hapticlab/core/measurement.hpp"
#include "hapticlab/modeling/workbench.hpp"
#include "hapticlab/stats/plot.hpp"
#include "workbench_cli.hpp"

namespace hapticlab::cli::workbench_cli {

using namespace modeling::wb;

namespace {

struct FitArgs {
  std::string measurement, model, out;
  std::vector<std::string> add;
  bool json = false, quiet = false;
};

// What the fit reports: the fit on all data, the friction bootstrap, and the errors before
// and after, on all data and held out.
struct FitOutcome {
  FitReport rep;
  BootstrapReport boot;
  Errors e_before, e_after, h_before, h_after;
};

// "Before" is the given model as it is, or (no --model) the baseline fitted; without --add
// and --model, before and after are the same fit and are reported once.
Errors ErrorsBefore(const FitArgs& o, const Model& start, const Replay& r, const Errors& e_after,
                    Progress& prog) {
  const bool given = !o.model.empty();
  if (!given && !o.add.empty()) {
    Model before = start;
    prog.Line("fit: fitting the baseline on all data");
    Fit(&before, r);
    return ComputeErrors(r, Predict(before, r), Split::kAll);
  }
  if (given) return ComputeErrors(r, Predict(start, r), Split::kAll);
  return e_after;
}

// The held-out errors: fitted on the training blocks, scored on the held-out ones (before
// --add only when there is an --add).
void HeldOutErrors(const FitArgs& o, const Model& start, const Replay& r, Progress& prog,
                   FitOutcome& x) {
  prog.Line("fit: fitting on the training blocks for the held-out errors");
  Model hb = start, ha = start;
  AddEffects(&ha, o.add, r);
  Fit(&ha, r, {.split = Split::kTrain});
  x.h_after = ComputeErrors(r, Predict(ha, r), Split::kHeldOut);
  x.h_before = x.h_after;
  if (!o.add.empty()) {
    Fit(&hb, r, {.split = Split::kTrain});
    x.h_before = ComputeErrors(r, Predict(hb, r), Split::kHeldOut);
  }
}

// Fits `after` (start plus --add) on all data with uncertainties, then the errors.
FitOutcome FitAndScore(const FitArgs& o, const Model& start, Model* after, const Replay& r,
                       const Measurement& measured, const ReplayOptions& replayed, Progress& prog) {
  FitOutcome x;
  prog.Line("fit: fitting on all data (with uncertainties)");
  x.rep = Fit(after, r, {.uncertainty = true});
  // The friction channel as `model fit-contact` reports it: bias-corrected, with standard
  // errors through the preprocessing (workbench_bootstrap.hpp).
  if (auto* cf = x.rep.Find(Channel::kFriction); cf && cf->summary.usable) {
    prog.Line("fit: friction through the preprocessing (parametric bootstrap)");
    x.boot = BootstrapFriction(after, measured, replayed, {.uncertainty = true}, cf);
  }
  x.e_after = ComputeErrors(r, Predict(*after, r), Split::kAll);
  x.e_before = ErrorsBefore(o, start, r, x.e_after, prog);
  HeldOutErrors(o, start, r, prog, x);
  return x;
}

nlohmann::json FitJson(const std::string& out, const Model& after, const FitOutcome& x) {
  nlohmann::json params;
  for (const auto& [e, ps] : after.params)
    for (const auto& [k, v] : ps) params[e][k] = v;
  auto j = nlohmann::json{
      {"before", ErrorsJson(x.e_before)},
      {"after", ErrorsJson(x.e_after)},
      {"held_out", {{"before", ErrorsJson(x.h_before)}, {"after", ErrorsJson(x.h_after)}}},
      {"effects", after.effects},
      {"params", params},
      {"out", out}};
  j.update(FitReportJson(x.rep));
  if (x.rep.Find(Channel::kFriction)) j["friction_bootstrap"] = BootstrapJson(x.boot);
  return j;
}

void PrintFit(const FitArgs& o, const Model& after, const FitOutcome& x) {
  const bool given = !o.model.empty();
  fmt::print("effects: {}\n", fmt::join(after.effects, ", "));
  if (given || !o.add.empty()) {
    fmt::print("before ({}): {}\n", given ? "model as given" : "baseline, fitted",
               ErrorsLine(x.e_before));
    fmt::print("after  (fitted):          {}\n", ErrorsLine(x.e_after));
    if (!o.add.empty()) fmt::print("held out, before: {}\n", ErrorsLine(x.h_before));
    fmt::print("held out{}: {}\n", o.add.empty() ? "" : ", after ", ErrorsLine(x.h_after));
  } else {
    fmt::print("fitted:   {}\n", ErrorsLine(x.e_after));
    fmt::print("held out: {}\n", ErrorsLine(x.h_after));
  }
  for (const auto& c : x.rep.channels) {
    fmt::print("{}\n", FitSummaryLine(c.summary));
    for (const auto& p : c.params)
      fmt::print("  {}.{} = {:.6g} +- {:.2g} (95 %: {:.6g} .. {:.6g}){}\n", p.effect, p.name,
                 p.value, p.sd, p.lo95, p.hi95, p.at_bound ? "  AT A BOUND" : "");
  }
  if (x.rep.Find(Channel::kFriction)) fmt::print("{}\n", BootstrapLine(x.boot));
  fmt::print("wrote {}\n", o.out);
}

int RunFit(const FitArgs& o) {
  RequireKnownEffects(o.add, "<command line>", "--add");
  Progress prog;
  prog.quiet = o.quiet;
  Model start;
  const bool given = !o.model.empty();
  if (given) start = LoadModel(o.model);
  prog.Line(fmt::format("fit: reading {}", o.measurement));
  Measurement measured;
  ReplayOptions replayed;
  const auto r = Load(o.measurement, given ? &start : nullptr, &measured, &replayed);
  if (!given) AddEffects(&start, BaselineEffects(), r);
  Model after = start;
  AddEffects(&after, o.add, r);
  const FitOutcome x = FitAndScore(o, start, &after, r, measured, replayed, prog);
  if (after.name.empty()) after.name = std::filesystem::path(o.out).stem().string();
  SaveModel(after, o.out, &r);
  if (o.json)
    PrintJson(FitJson(o.out, after, x));
  else
    PrintFit(o, after, x);
  if (!x.rep.IsUsable()) {
    fmt::print(stderr,
               "fit: a channel's fit is not usable (see the fit lines); {} was written for "
               "inspection\n",
               o.out);
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

void AddFit(CLI::App& app) {
  auto o = std::make_shared<FitArgs>();
  auto* cmd = app.add_subcommand(
      "fit",
      "Fit a material model to a measurement: the thesis's baseline (coulomb, viscous, dahl,\n"
      "hc-damping, hc-exponent, vibration-speed, vibration-force) when no --model is given,\n"
      "plus every --add effect. The contact channels use the same engine as `model fit-contact`\n"
      "(Algorithm 1, then a joint Ceres refinement of the vector Dahl replay). Prints the error\n"
      "(before and after when there is a change), on all data and held out (fitted on the even\n"
      "1 s blocks, scored on the odd ones), each solve's termination, iterations, cost and\n"
      "parameters at bounds, the parameters with 95 % intervals (cluster jackknife over\n"
      "3 s clusters of blocks; friction's bias-corrected and its standard errors the larger of\n"
      "that and a parametric bootstrap through the preprocessing, as `model fit-contact`), and\n"
      "writes the fitted model (a material TOML the renderer plays, "
      "with a\n"
      "[workbench] table of every parameter). Progress goes to stderr unless --quiet.");
  cmd->add_option("--measurement", o->measurement,
                  "Measurement CSV v1 (with acc_mps2 for the vibration channel)")
      ->required();
  cmd->add_option("--model", o->model,
                  "Start from this model (workbench or renderer material TOML)");
  cmd->add_option("--add", o->add, "Effect to add (repeatable); one of: " + CatalogueNames());
  cmd->add_option("-o,--out", o->out, "Fitted model to write (.toml)")->required();
  cmd->add_flag("--json", o->json,
                "Print {before, after, held_out:{before, after}, effects, params, estimates, fits, "
                "usable} as JSON");
  cmd->add_flag("--quiet", o->quiet, "No progress lines on stderr");
  cmd->callback([o] { RunGuarded([&] { return RunFit(*o); }); });
}

}  // namespace hapticlab::cli::workbench_cli
