// hapticlab diagnose: the effects a model lacks, ranked by held-out error reduction
// (docs/workbench.md).

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
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

struct DiagnoseArgs {
  std::string measurement, model;
  bool json = false, quiet = false;
  int threads = 0;
};

// The progress line on stderr: a bar on a terminal, a line per candidate otherwise (the
// candidates are fitted in parallel, hence the mutex).
std::function<void(const std::string&, int, int)> DiagnoseProgress(std::mutex& mu, bool tty) {
  return [&mu, tty](const std::string& effect, int done, int total) {
    std::lock_guard<std::mutex> lock(mu);
    if (tty) {
      const int w = 30, filled = w * done / std::max(total, 1);
      fmt::print(stderr, "\rdiagnose [{}{}] {}/{} ({}){:20s}", std::string(filled, '#'),
                 std::string(w - filled, '.'), done, total, effect, "");
      if (done == total) fmt::print(stderr, "\n");
    } else {
      fmt::print(stderr, "diagnose: {}/{} candidates fitted ({})\n", done, total, effect);
    }
  };
}

nlohmann::json DiagnosisJson(const Diagnosis& dx, const std::string& vib_note) {
  const auto& u = dx.unexplained;
  nlohmann::json c = nlohmann::json::array();
  for (const auto& x : dx.candidates)
    c.push_back({{"effect", x.effect},
                 {"channel", ChannelName(x.channel)},
                 {"error_after", x.error_after},
                 {"error_reduction", x.error_reduction},
                 {"relative_reduction", x.relative_reduction},
                 {"t", x.t_statistic},
                 {"supported", x.supported},
                 {"params", x.params},
                 {"evidence", x.evidence},
                 {"confounded_with", x.confounded_with},
                 {"fit", FitSummaryJson(x.fit)},
                 {"rejected", x.rejected}});
  nlohmann::json ch = nlohmann::json::array(), ax = nlohmann::json::array();
  for (const auto& x : u.channels)
    ch.push_back({{"channel", ChannelName(x.channel)},
                  {"error", x.error},
                  {"noise_floor", x.noise_floor},
                  {"ratio", x.ratio}});
  for (const auto& x : u.axes)
    ax.push_back({{"axis", x.axis},
                  {"channel", ChannelName(x.channel)},
                  {"share", x.share},
                  {"description", x.description}});
  nlohmann::json base = nlohmann::json::object();
  for (const auto& [k, v] : dx.baseline_channel) base[ChannelName(k)] = v;
  return nlohmann::json{
      {"baseline_error", dx.baseline_error},
      {"baseline_channels", base},
      {"candidates", c},
      {"unexplained",
       {{"channels", ch}, {"axes", ax}, {"flagged", u.flagged}, {"summary", u.summary}}},
      {"vibration_model", vib_note},
      {"vibration_by_condition", EsCellsJson(dx.vibration_by_condition)}};
}

// The candidates, best first: their held-out errors, evidence and (supported) parameters.
void PrintCandidates(const Diagnosis& dx) {
  int rank = 0;
  for (const auto& x : dx.candidates) {
    fmt::print("{}. {} ({}): held-out error {:.4f} ({:+.4f}; {} error {:+.1f} %, t = {:.1f}) {}\n",
               ++rank, x.effect, ChannelName(x.channel), x.error_after, -x.error_reduction,
               ChannelName(x.channel), -100 * x.relative_reduction, x.t_statistic,
               x.supported ? "SUPPORTED" : "not supported");
    fmt::print("   {}\n", x.evidence);
    if (x.supported) {
      std::string ps;
      for (const auto& [k, v] : x.params)
        ps += fmt::format("{}{} = {:.4g}", ps.empty() ? "" : ", ", k, v);
      fmt::print("   fitted: {}\n", ps);
    }
  }
}

// Each channel's error against its noise floor, and where the residual lives.
void PrintUnexplained(const Unexplained& u) {
  fmt::print(
      "\nunexplained (held-out error against the noise floor estimated from the "
      "measurement):\n");
  for (const auto& x : u.channels)
    fmt::print("  {:13s} error {:.4f}, floor {:.4f}, {:.1f}x\n", ChannelName(x.channel), x.error,
               x.noise_floor, x.ratio);
  fmt::print(
      "where the residual lives (share of a channel's residual variance along each axis):\n");
  for (std::size_t k = 0; k < u.axes.size() && k < 6; ++k)
    fmt::print("  {:9s} {:13s} {:5.1f} %  {}\n", u.axes[k].axis, ChannelName(u.axes[k].channel),
               100 * u.axes[k].share, u.axes[k].description);
}

void PrintDiagnosis(const Diagnosis& dx, const std::string& model, const std::string& vib_note) {
  const auto& u = dx.unexplained;
  if (u.flagged) fmt::print("{}\n\n", u.summary);
  if (!vib_note.empty()) fmt::print("{}\n\n", vib_note);
  fmt::print("held-out error of {} (refitted on the training blocks): {:.4f}", model,
             dx.baseline_error);
  for (const auto& [k, v] : dx.baseline_channel) fmt::print(", {} {:.4f}", ChannelName(k), v);
  fmt::print("\n");
  PrintEsCells("held-out vibration E_s by speed and force", dx.vibration_by_condition);
  fmt::print("\n");
  PrintCandidates(dx);
  PrintUnexplained(u);
  if (!u.flagged) fmt::print("{}\n", u.summary);
}

int RunDiagnose(const DiagnoseArgs& o) {
  auto m = LoadModel(o.model);
  const std::string vib_note = AttachVibration(o.model, &m);
  const auto r = Load(o.measurement, &m);
  std::mutex mu;
  DiagnoseOptions opt;
  opt.threads = o.threads;
  if (!o.quiet) {
    fmt::print(stderr, "diagnose: refitting {} on the training blocks, then each candidate\n",
               o.model);
    opt.progress = DiagnoseProgress(mu, isatty(fileno(stderr)));
  }
  const auto dx = Diagnose(m, r, opt);
  if (o.json)
    PrintJson(DiagnosisJson(dx, vib_note));
  else
    PrintDiagnosis(dx, o.model, vib_note);
  return kExitOk;
}

}  // namespace

void AddDiagnose(CLI::App& app) {
  auto o = std::make_shared<DiagnoseArgs>();
  auto* cmd = app.add_subcommand(
      "diagnose",
      "For every catalogue effect the model lacks: add it, fit on the training blocks (even 1 s\n"
      "blocks) and score on the held-out blocks; rank by held-out error reduction. An effect is\n"
      "supported when its channel's held-out error falls by at least 2 %, the per-block paired t\n"
      "(log error ratio) is at least 3, its fit converged with none of its parameters at a bound,\n"
      "and the residual pattern it produces is there; only then does its evidence name a cause.\n"
      "Supported effects that change the prediction the same way are reported as confounded.\n"
      "Then what is unexplained: each channel's held-out error against its noise floor (estimated\n"
      "from the measurement) and where the residual lives (time, speed, load, direction, "
      "position,\n"
      "regime, band; share of its variance, shape in words). When nothing is supported but an\n"
      "error is 1.5x its floor or more, that is said first. Progress on stderr unless --quiet.");
  cmd->add_option("--model", o->model, "Model (workbench or renderer material TOML)")->required();
  cmd->add_option("--measurement", o->measurement, "Measurement CSV v1")->required();
  cmd->add_flag(
      "--json", o->json,
      "Print {\"baseline_error\", \"candidates\": [{effect, error_after, error_reduction, params, "
      "evidence, fit, rejected, ...}], \"unexplained\": {\"channels\": [...], \"axes\": [...]}}");
  cmd->add_flag("--quiet", o->quiet, "No progress on stderr");
  cmd->add_option("--threads", o->threads, "Candidates fitted in parallel (0: all cores)")
      ->capture_default_str();
  cmd->callback([o] { RunGuarded([&] { return RunDiagnose(*o); }); });
}

}  // namespace hapticlab::cli::workbench_cli
