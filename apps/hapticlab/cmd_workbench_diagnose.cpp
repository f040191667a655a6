// hapticlab diagnose: the effects a model lacks, ranked by held-out error reduction
// (docs/workbench.md).

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

void AddDiagnose(CLI::App& app) {
  struct O {
    std::string measurement, model;
    bool json = false, quiet = false;
    int threads = 0;
  };
  auto o = std::make_shared<O>();
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
  cmd->callback([o] {
    RunGuarded([&] {
      auto m = LoadModel(o->model);
      const std::string vib_note = AttachVibration(o->model, &m);
      const auto r = Load(o->measurement, &m);
      std::mutex mu;
      DiagnoseOptions opt;
      opt.threads = o->threads;
      const bool tty = isatty(fileno(stderr));
      if (!o->quiet) {
        fmt::print(stderr, "diagnose: refitting {} on the training blocks, then each candidate\n",
                   o->model);
        opt.progress = [&, tty](const std::string& effect, int done, int total) {
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
      const auto dx = Diagnose(m, r, opt);
      const auto& u = dx.unexplained;
      if (o->json) {
        nlohmann::json c = nlohmann::json::array();
        for (const auto& x : dx.candidates)
          c.push_back({{"effect", x.effect},
                       {"channel", x.channel},
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
          ch.push_back({{"channel", x.channel},
                        {"error", x.error},
                        {"noise_floor", x.noise_floor},
                        {"ratio", x.ratio}});
        for (const auto& x : u.axes)
          ax.push_back({{"axis", x.axis},
                        {"channel", x.channel},
                        {"share", x.share},
                        {"description", x.description}});
        PrintJson(nlohmann::json{
            {"baseline_error", dx.baseline_error},
            {"baseline_channels", dx.baseline_channel},
            {"candidates", c},
            {"unexplained",
             {{"channels", ch}, {"axes", ax}, {"flagged", u.flagged}, {"summary", u.summary}}},
            {"vibration_model", vib_note},
            {"vibration_by_condition", EsCellsJson(dx.vibration_by_condition)}});
        return kExitOk;
      }
      if (u.flagged) fmt::print("{}\n\n", u.summary);
      if (!vib_note.empty()) fmt::print("{}\n\n", vib_note);
      fmt::print("held-out error of {} (refitted on the training blocks): {:.4f}", o->model,
                 dx.baseline_error);
      for (const auto& [k, v] : dx.baseline_channel) fmt::print(", {} {:.4f}", k, v);
      fmt::print("\n");
      PrintEsCells("held-out vibration E_s by speed and force", dx.vibration_by_condition);
      fmt::print("\n");
      int rank = 0;
      for (const auto& x : dx.candidates) {
        fmt::print(
            "{}. {} ({}): held-out error {:.4f} ({:+.4f}; {} error {:+.1f} %, t = {:.1f}) {}\n",
            ++rank, x.effect, x.channel, x.error_after, -x.error_reduction, x.channel,
            -100 * x.relative_reduction, x.t_statistic,
            x.supported ? "SUPPORTED" : "not supported");
        fmt::print("   {}\n", x.evidence);
        if (x.supported) {
          std::string ps;
          for (const auto& [k, v] : x.params)
            ps += fmt::format("{}{} = {:.4g}", ps.empty() ? "" : ", ", k, v);
          fmt::print("   fitted: {}\n", ps);
        }
      }
      fmt::print(
          "\nunexplained (held-out error against the noise floor estimated from the "
          "measurement):\n");
      for (const auto& x : u.channels)
        fmt::print("  {:13s} error {:.4f}, floor {:.4f}, {:.1f}x\n", x.channel, x.error,
                   x.noise_floor, x.ratio);
      fmt::print(
          "where the residual lives (share of a channel's residual variance along each axis):\n");
      for (std::size_t k = 0; k < u.axes.size() && k < 6; ++k)
        fmt::print("  {:9s} {:13s} {:5.1f} %  {}\n", u.axes[k].axis, u.axes[k].channel,
                   100 * u.axes[k].share, u.axes[k].description);
      if (!u.flagged) fmt::print("{}\n", u.summary);
      return kExitOk;
    });
  });
}

}  // namespace hapticlab::cli::workbench_cli
